"""The run history (SQLite or PostgreSQL), its spool, its web page, and the acceptance certificate: what goods-in
keeps per serial number.

db.py: what the rest of the suite calls (``record_run``, ``list_runs``, ``get_run``, ``history_path``); target.py:
where the history is (a file or a postgresql:// URL); schema.py: the tables and their versions; backend.py,
dbapi.py, store_sqlite.py, store_postgres.py: one connection, whichever the database; records.py: one run in, once;
spool.py and sync.py: a record waits on the station's disk until the database has it; web/: ``history serve``;
certificate.py: ``render_certificate`` (RunSummary -> HTML) and ``write_certificate``; views.py: what ``history``
prints (its arguments: cli/history.py). The pytest side is plugin/history_hook.py. Nothing is imported here, so the
command line stays light at start-up.
"""
