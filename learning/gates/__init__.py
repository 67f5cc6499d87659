"""Per-mode gates h_j: window → {0, 1} (predictable or not), and their scores.

- :mod:`learning.gates.gate` — calibrated per-mode classifiers :class:`ModeGates`;
- :mod:`learning.gates.metrics` — accuracy, F1 and Brier score per mode (``gate_metrics``).
"""

from learning.gates.gate import ConstantGate, ModeGates, check_gate_inputs, check_gate_labels
from learning.gates.metrics import gate_metrics

__all__ = ["ConstantGate", "ModeGates", "check_gate_inputs", "check_gate_labels", "gate_metrics"]
