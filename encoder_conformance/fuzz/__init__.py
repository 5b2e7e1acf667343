"""SDO fuzzing against a device (CiA 301 §7.2.4.3): what may be sent (``exclusions``, ``strategies``),
how it is sent and judged (``runner``, ``attribution``, ``oracle``, ``watch``) and how a failure is
shown (``replay``). Used by suites/test_sdo_fuzz.py."""
