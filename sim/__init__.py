"""Simulation: synthetic demonstrations and the console script's simulator subcommands.

- :mod:`sim.demonstrator` — synthetic bimanual-eating demonstrations.
- :mod:`sim.cli` — the ``mpcshare`` console script (``generate``, ``demo`` on top of the core).
"""
