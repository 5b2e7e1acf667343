"""An independent CiA 406 encoder device (written from the text, not from this project's model or twin), the
bus it joins, and the shaft-drive plug-in that turns its shaft: used to prove the suites catch real faults."""
