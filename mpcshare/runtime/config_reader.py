"""Reading the TOML of ``mpcshare run``'s configuration: typed values with one-line errors, field paths checked.

:class:`TableReader` reads numbers, strings, flags, lists, topics and QoS from a table and raises
:class:`RunConfigError` as ``FILE, [table] key: what is wrong``. :func:`check_field_path` checks that a
field path of ``mpcshare import``'s mapping leads from a message type of :mod:`mpcshare.runtime.messages`
to a number (or to a quaternion, with an angle).
"""

from __future__ import annotations

import math
import typing
from dataclasses import fields, is_dataclass
from typing import Any, Sequence

from cyclonedds.idl.types import array, sequence

from learning.data.mapping import FieldPath
from mpcshare.errors import MpcshareError
from mpcshare.runtime.messages import Quaternion, dds_topic
from mpcshare.runtime.transport import RELIABILITIES, QosSettings

__all__ = ["RunConfigError", "TableReader", "check_field_path"]


class RunConfigError(MpcshareError, ValueError):
    """A configuration ``mpcshare run`` cannot use; the message names the file, the table and the key."""


class TableReader:
    """Typed reads from the TOML document, raising :class:`RunConfigError` with the file, table and key."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, where: str, message: str) -> RunConfigError:
        return RunConfigError(f"{self.source}, {where}: {message}")

    def table(self, doc: dict, key: str, where: str, required: bool = False) -> dict:
        value = doc.get(key)
        if value is None:
            if required:
                raise self.fail(where, "missing (a required table)")
            return {}
        if not isinstance(value, dict):
            raise self.fail(where, f"must be a table, got {value!r}")
        return value

    def keys(self, table: dict, allowed: Sequence[str], where: str) -> None:
        unknown = [k for k in table if k not in allowed]
        if unknown:
            raise self.fail(f"{where} {unknown[0]}", f"unknown key (allowed: {', '.join(allowed)})")

    def number(self, table: dict, key: str, where: str, default: float | None = None, *, low: float = 0.0,
               high: float = math.inf, required: bool = False) -> float | None:
        if key not in table:
            if required:
                raise self.fail(f"{where} {key}", "missing")
            return default
        v = table[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and low < v <= high):
            bound = f"in ({low:g}, {high:g}]" if math.isfinite(high) else f"> {low:g}"
            raise self.fail(f"{where} {key}", f"must be a number {bound}, got {v!r}")
        return float(v)

    def text(self, table: dict, key: str, where: str, default: str | None = None,
             choices: Sequence[str] | None = None) -> str:
        if key not in table:
            if default is None:
                raise self.fail(f"{where} {key}", "missing")
            return default
        v = table[key]
        if not isinstance(v, str):
            raise self.fail(f"{where} {key}", f"must be a string, got {v!r}")
        if choices is not None and v not in choices:
            raise self.fail(f"{where} {key}", f"{v!r} is not one of {', '.join(choices)}")
        return v

    def flag(self, table: dict, key: str, where: str, default: bool) -> bool:
        v = table.get(key, default)
        if not isinstance(v, bool):
            raise self.fail(f"{where} {key}", f"must be true or false, got {v!r}")
        return v

    def strings(self, table: dict, key: str, where: str, default: Sequence[str] = ()) -> tuple[str, ...]:
        v = table.get(key, list(default))
        if not isinstance(v, list) or not all(isinstance(x, str) and x for x in v):
            raise self.fail(f"{where} {key}", f"must be a list of non-empty strings, got {v!r}")
        return tuple(v)

    def triple(self, table: dict, key: str, where: str) -> tuple[float, float, float] | None:
        if key not in table:
            return None
        v = table[key]
        if not (isinstance(v, list) and len(v) == 3 and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                           and math.isfinite(x) for x in v)):
            raise self.fail(f"{where} {key}", f"must be three numbers [x, y, z], got {v!r}")
        return (float(v[0]), float(v[1]), float(v[2]))

    def topic(self, table: dict, where: str) -> str:
        t = self.text(table, "topic", where)
        try:
            dds_topic(t)
        except ValueError as exc:
            raise self.fail(f"{where} topic", str(exc)) from None
        return t

    def qos(self, table: dict, where: str, default: QosSettings) -> QosSettings:
        rel = self.text(table, "reliability", where, default.reliability, RELIABILITIES)
        depth = table.get("depth", default.depth)
        if isinstance(depth, bool) or not isinstance(depth, int) or not 1 <= depth <= 1000:
            raise self.fail(f"{where} depth", f"must be an integer in [1, 1000], got {depth!r}")
        return QosSettings(rel, depth)


def _kind(tp: Any) -> tuple[str, Any]:
    """("struct", class), ("seq", element type), ("num", None) or ("str", None) of a field's annotation."""
    if isinstance(tp, type) and is_dataclass(tp):
        return "struct", tp
    if typing.get_origin(tp) is typing.Annotated:
        base, *meta = typing.get_args(tp)
        for m in meta:
            if isinstance(m, (sequence, array)):
                return "seq", m.subtype
        return _kind(base)
    if tp in (int, float):
        return "num", None
    return "str", None


def check_field_path(message: type, path: FieldPath) -> None:
    """ValueError unless ``path`` leads from ``message`` to a number (or to a quaternion with an angle)."""
    kind, tp = "struct", message
    for step in path.steps:
        if isinstance(step, str):
            if kind != "struct":
                raise ValueError(f"field path {path.text!r}: {step!r} follows a value that has no fields")
            names = [f.name for f in fields(tp)]
            if step not in names:
                raise ValueError(f"field path {path.text!r}: {tp.__name__} has no field {step!r} "
                                 f"(fields: {', '.join(names)})")
            kind, tp = _kind(typing.get_type_hints(tp, include_extras=True)[step])
        else:
            if kind != "seq":
                raise ValueError(f"field path {path.text!r}: [{step}] indexes a value that is not an array")
            kind, tp = _kind(tp)
    if path.angle is not None:
        if tp is not Quaternion:
            raise ValueError(f"field path {path.text!r}: @{path.angle} needs a quaternion (e.g. pose.orientation)")
    elif kind != "num":
        raise ValueError(f"field path {path.text!r} ends at a {'message' if kind == 'struct' else kind}, "
                         "not a number")
