"""The simulated twin, in two faces (DESIGN.md §2). The top level is the tester-side API, the only part of ``sim/``
imported outside it: starting a twin as a process of its own and its control client (``process.py``, ``forked.py``),
the control channel's commands (``control.py``), the twin's entry points (``twin.py``: serve, in this process,
what a variant overrides) and the catalogue of faults and variants (``fault_catalogue.py``, ``hold_faults.py``;
data). ``engine/`` is the protocol engine the twin's process runs, on raw python-can frames (DESIGN.md §3).
Importing the API loads none of the engine. Suites never import this package.
"""
