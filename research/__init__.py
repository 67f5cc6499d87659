"""Research beside the product: bounds and hindsight searches that explain its results; not installed, and
no product package imports it (``tests/test_layering.py``). Benchmarks and tests import it from the
repository root (``docs/design.md``, "Layout and layering")."""
