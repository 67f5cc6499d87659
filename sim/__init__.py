"""Simulation: the world the controller acts in.

- :mod:`sim.demonstrator` — synthetic bimanual-eating demonstrations.

``sim`` imports ``learning`` and ``robot``, never ``mpcshare``: the command line
that runs it (``mpcshare generate``, ``mpcshare demo``) lives in :mod:`mpcshare.cli`.
"""
