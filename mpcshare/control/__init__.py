"""The online shared controller, every 10 ms.

- :mod:`mpcshare.control.controller` — :class:`SharedController` (``step`` never raises);
- :mod:`mpcshare.control.types` — its output :class:`ControlCommand`, :class:`ControllerConfig`
  and the ranked status names;
- :mod:`mpcshare.control.frontend` — the streaming front end (Kalman filter, anti-aliased
  history, model ticks);
- :mod:`mpcshare.control.arbitration` — α, β and the fusion û = α·û_r + β·û_v;
- :mod:`mpcshare.control.strategies` — the arbitration strategies, one module each, in ``REGISTRY``;
- :mod:`mpcshare.control.setup` — checking a bundle against the controller and building the MPC;
- :mod:`mpcshare.control.workspace` — frames (the base pose) and the workspace box.
"""

from mpcshare.control.controller import SharedController
from mpcshare.control.types import STATUSES, ControlCommand, ControllerConfig

__all__ = ["STATUSES", "ControlCommand", "ControllerConfig", "SharedController"]
