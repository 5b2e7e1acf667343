"""What the suites use beside their fixtures: assertion helpers that name expected, observed and the frames
(``checks``), the parameters a test may change safely (``parameters``), and the helpers of one area each that
need pytest or the evidence (``cam``, ``emcy``, ``lss``, ``periodic``, ``tpdo``, ``work_area``, ``teardown``).
Device-handling code without pytest lives in ``dut/``."""
