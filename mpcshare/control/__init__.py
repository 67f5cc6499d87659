"""The online shared controller, every 10 ms.

- :mod:`mpcshare.control.controller` — :class:`SharedController` (``step`` never raises);
  :mod:`mpcshare.control.types` — :class:`ControlCommand`, :class:`ControllerConfig`, the ranked statuses;
- :mod:`mpcshare.control.builder` — the one builder of the parts (the QP once, with its whole constraint
  list; the MPC, the front end, the arbiter); :mod:`mpcshare.control.records` — the typed records the
  stages of a step hand each other;
- :mod:`mpcshare.control.sensing` — the sensing stage (front end, learned parts on model ticks, the
  control-rate forecast); :mod:`mpcshare.control.frontend` — Kalman filter, anti-aliased history, ticks;
- :mod:`mpcshare.control.forecast` — the forecast as a tip trajectory; :mod:`mpcshare.control.fastpath` —
  the control-rate forecast; :mod:`mpcshare.control.preview` — the MPC's preview;
  :mod:`mpcshare.control.mpc_follow` — the MPC solved every few steps and followed;
- :mod:`mpcshare.control.keepout` — the knife kept out of the wearer's body zones;
  :mod:`mpcshare.control.holding` — braking, holding and the last-resort commands;
- :mod:`mpcshare.control.arbitration` — α, β and û = α·û_r + β·û_v; :mod:`mpcshare.control.strategies` —
  the strategies, one module each, in ``REGISTRY``;
- :mod:`mpcshare.control.bundle_inputs` — what the controller takes from a bundle, checked;
  :mod:`mpcshare.control.workspace` — frames (the base pose) and the workspace box.
"""

from mpcshare.control.controller import SharedController
from mpcshare.control.types import STATUSES, ControlCommand, ControllerConfig

__all__ = ["STATUSES", "ControlCommand", "ControllerConfig", "SharedController"]
