"""The online shared controller, every 10 ms.

- :mod:`mpcshare.control.controller` — :class:`SharedController` (``step`` never raises);
- :mod:`mpcshare.control.types` — its output :class:`ControlCommand`, :class:`ControllerConfig`
  and the ranked status names;
- :mod:`mpcshare.control.builder` — the one builder of the controller's parts (the QP built once with its
  whole constraint list, the MPC, the front end, the arbiter);
- :mod:`mpcshare.control.records` — the typed records the stages of a step hand each other (what was
  sensed, the arbitration, the tracking);
- :mod:`mpcshare.control.sensing` — the sensing stage: the front end stepped, the learned parts (the gate
  and the streaming predictor on a model tick, the control-rate forecast every step);
- :mod:`mpcshare.control.frontend` — the streaming front end (Kalman filter, anti-aliased
  history, model ticks);
- :mod:`mpcshare.control.forecast` — the forecast as a tip trajectory; :mod:`mpcshare.control.fastpath` —
  the control-rate forecast;
- :mod:`mpcshare.control.preview` — the MPC's preview of the tip reference over its horizon;
- :mod:`mpcshare.control.mpc_follow` — solving the MPC every few steps and following its plan;
- :mod:`mpcshare.control.keepout` — keeping the knife out of the wearer's body zones;
- :mod:`mpcshare.control.holding` — braking and holding when a step cannot run whole, and the last-resort
  commands when it fails unexpectedly;
- :mod:`mpcshare.control.arbitration` — α, β and the fusion û = α·û_r + β·û_v;
- :mod:`mpcshare.control.strategies` — the arbitration strategies, one module each, in ``REGISTRY``;
- :mod:`mpcshare.control.bundle_inputs` — what the controller takes from a bundle, checked (channels, the
  learned parts, the shoulder map, the mode figures, the rule's settings);
- :mod:`mpcshare.control.workspace` — frames (the base pose) and the workspace box.
"""

from mpcshare.control.controller import SharedController
from mpcshare.control.types import STATUSES, ControlCommand, ControllerConfig

__all__ = ["STATUSES", "ControlCommand", "ControllerConfig", "SharedController"]
