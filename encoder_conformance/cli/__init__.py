"""The ``encoder-conformance`` command line: ``main`` holds the table of commands, one module per command
(run, accept, restore, lss, readings, history) and ``usage`` for the one-line usage errors they share."""
