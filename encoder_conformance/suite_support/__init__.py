"""What the suites use beside their fixtures: assertion helpers that name expected, observed and the
frames (checks), and the parameters a test may change safely (parameters)."""
