"""The ``encoder-conformance`` command line: ``main`` holds the table of commands (``COMMANDS``), one module
per command or family (run, accept, restore, lss, history, readings, firmware-ci, sim, profile, faults, vcan;
``*_actions`` modules do the work that imports the DUT layer, kept out of start-up) and ``usage`` for the
one-line usage errors and argument types they share."""
