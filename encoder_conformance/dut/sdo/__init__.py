"""SDO: the byte-exact client and its raw frames, words for a failure's frames, a patient read for custody, the identity
read, what the start-up check's frames show."""
