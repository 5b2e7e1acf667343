"""The pytest plugin of the conformance suite: options, capability selection, outcomes and verdicts, evidence,
bus traces, progress, the run record and the reports."""
