"""The self-tests never write into the repository's reports/history.sqlite: every conformance run they start,
in this process or a child process, records into a temporary history database instead."""

from __future__ import annotations

import pytest

from encoder_conformance.history.db import ENV_VAR


@pytest.fixture(autouse=True, scope="session")
def _history_in_a_temporary_file(tmp_path_factory):
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(ENV_VAR, str(tmp_path_factory.mktemp("history") / "history.sqlite"))
        yield
