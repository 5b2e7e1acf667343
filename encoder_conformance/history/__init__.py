"""The run history (SQLite) and the acceptance certificate: what a goods-in station keeps per serial number.

db.py: ``record_run(summary, db_path)`` appends a run, ``history_path`` says where the database is;
certificate.py: ``render_certificate`` (RunSummary -> HTML) and ``write_certificate``; views.py: what
``history`` prints (its arguments: cli/history.py). The pytest side is plugin/history_hook.py. Nothing is imported
here, so the command line stays light at start-up.
"""
