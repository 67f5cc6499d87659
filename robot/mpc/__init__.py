"""The knife-tip MPC (CasADi): joint accelerations over a short horizon within every joint limit.

- :mod:`robot.mpc.tip_mpc` — :class:`TipMPC`, the solver front (RTI with DAQP by default) and
  :class:`MPCResult`;
- :mod:`robot.mpc.problem` — the condensed problem and its :class:`Weights`;
- :mod:`robot.mpc.qp` — the QP back-ends of the real-time iteration;
- :mod:`robot.mpc.nlp` — the multiple-shooting NLP for CasADi's ``nlpsol`` solvers;
- :mod:`robot.mpc.symbolic` — the arm's kinematics and dynamics as CasADi expressions;
- :mod:`robot.mpc.codegen` — compiling CasADi functions to C (cached, paths by argument).
"""

from robot.mpc.problem import Weights
from robot.mpc.tip_mpc import MPCResult, TipMPC

__all__ = ["MPCResult", "TipMPC", "Weights"]
