"""cyclonedds IDL types for tyre_msgs, built at import time from the .msg files.

The .msg files in ``msgs/msg`` (and the standard ones embedded in ``msgs/std``) stay the single
source of truth: this module parses them and builds one ``cyclonedds.idl.IdlStruct`` dataclass
per message, with the DDS type names ROS 2 uses on the wire
(``tyre_msgs::msg::dds_::RigSample_``, ``std_msgs::msg::dds_::Header_``, ...), so a plain
cyclonedds participant can publish and subscribe to the suite's topics (``rt/rig/sample``).

Usage::

    from tyre_msgs_idl import types
    RigSample = types["RigSample"]                  # tyre_msgs types by short name
    Header = types["std_msgs/msg/Header"]           # any type by its ROS 2 name
    s = RigSample(header=Header(frame_id="iso_w"), fx_n=-1.5)
    payload = s.serialize()                         # XCDR1, 4-byte header 00 01 00 00
    assert RigSample.deserialize(payload) == s
    RigSample.FAULT_ESTOP                           # .msg constants are class attributes

Every field has a default (0, 0.0, False, "", [] or a default nested message), so messages can
be built with keyword arguments for only the fields a test cares about.
"""

from __future__ import annotations

import dataclasses
import re
import types as _pytypes
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

from cyclonedds.idl import IdlStruct
from cyclonedds.idl import types as idl

__all__ = [
    "MsgDefError",
    "MsgField",
    "MsgConstant",
    "MsgDef",
    "parse_msg",
    "load",
    "types",
    "definitions",
    "MSGS_DIR",
]

#: The tyre_msgs package directory (``msgs/`` at the repository root).
MSGS_DIR = Path(__file__).resolve().parents[2] / "msgs"


class MsgDefError(ValueError):
    """A .msg file that does not parse; the message names the file and line."""

    def __init__(self, file: str, line: int, reason: str):
        super().__init__(f"{file}:{line}: {reason}")
        self.file = file
        self.line = line
        self.reason = reason


@dataclass
class MsgField:
    """One field: base type (primitive name or ``pkg/Name``), array kind and size."""

    base: str
    name: str
    array: Optional[str]  # None, "unbounded", "bounded" or "fixed"
    size: Optional[int]  # bound or fixed length
    string_bound: Optional[int]
    line: int


@dataclass
class MsgConstant:
    """One constant: primitive type, name and value (int, float, bool or str)."""

    type: str
    name: str
    value: Any
    line: int


@dataclass
class MsgDef:
    """A parsed .msg file."""

    package: str
    name: str
    fields: List[MsgField]
    constants: List[MsgConstant]

    @property
    def ros_type_name(self) -> str:
        return f"{self.package}/msg/{self.name}"

    @property
    def dds_type_name(self) -> str:
        return f"{self.package}::msg::dds_::{self.name}_"


_INT_RANGES = {
    "byte": (0, 255),
    "char": (0, 255),
    "int8": (-(2**7), 2**7 - 1),
    "uint8": (0, 2**8 - 1),
    "int16": (-(2**15), 2**15 - 1),
    "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1),
    "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint64": (0, 2**64 - 1),
}
_PRIMITIVES = set(_INT_RANGES) | {"bool", "float32", "float64", "string", "wstring"}
_FIELD_NAME = re.compile(r"^[a-z][a-z0-9_]*$")
_CONST_NAME = re.compile(r"^[A-Z][A-Z0-9_]*$")
_TYPE_REF = re.compile(r"^(?:([a-z][a-z0-9_]*)/(?:msg/)?)?([A-Z][A-Za-z0-9]*)$")
_ARRAY = re.compile(r"^(.*)\[(<=)?(\d*)\]$")


def _strip_comment(line: str) -> str:
    """Cut the line at the first ``#`` (rosidl does the same, even inside quotes)."""
    return line.split("#", 1)[0]


def _constant_value(ptype: str, text: str, err) -> Any:
    if ptype in _INT_RANGES:
        if not re.fullmatch(r"[+-]?\d+", text):
            raise err(f"constant value {text!r} is not a decimal integer")
        value = int(text)
        lo, hi = _INT_RANGES[ptype]
        if not lo <= value <= hi:
            raise err(f"constant value {value} out of range for {ptype}")
        return value
    if ptype in ("float32", "float64"):
        try:
            return float(text)
        except ValueError:
            raise err(f"constant value {text!r} is not a number") from None
    if ptype == "bool":
        low = text.lower()
        if low in ("true", "1"):
            return True
        if low in ("false", "0"):
            return False
        raise err(f"constant value {text!r} is not a bool")
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "\"'":
        return text[1:-1]
    return text


def parse_msg(package: str, name: str, text: str, file: str = "<msg>") -> MsgDef:
    """Parse .msg text. Unqualified type names resolve to ``package``."""
    fields: List[MsgField] = []
    constants: List[MsgConstant] = []
    seen = set()
    for lineno, raw in enumerate(text.splitlines(), start=1):

        def err(reason: str, _line=lineno) -> MsgDefError:
            return MsgDefError(file, _line, reason)

        code = _strip_comment(raw).strip()
        if not code:
            continue
        parts = code.split(None, 1)
        if len(parts) < 2:
            raise err(f"expected a name after type {parts[0]!r}")
        type_token, rest = parts[0], parts[1].strip()

        array = size = None
        m = _ARRAY.match(type_token)
        base = type_token
        if m:
            base = m.group(1)
            if m.group(3) == "":
                if m.group(2):
                    raise err(f"malformed array suffix in {type_token!r}")
                array = "unbounded"
            else:
                size = int(m.group(3))
                array = "bounded" if m.group(2) else "fixed"
        string_bound = None
        if base.startswith(("string<=", "wstring<=")):
            base, bound = base.split("<=", 1)
            if not bound.isdigit():
                raise err(f"malformed string bound in {type_token!r}")
            string_bound = int(bound)
        if base not in _PRIMITIVES:
            ref = _TYPE_REF.match(base)
            if not ref:
                raise err(f"unknown or malformed type {type_token!r}")
            base = f"{ref.group(1) or package}/{ref.group(2)}"

        if "=" in rest:
            # rosidl: any `=` after the type makes the line a constant.
            cname, value = (part.strip() for part in rest.split("=", 1))
            if not _CONST_NAME.match(cname):
                raise err(f"invalid constant name {cname!r}")
            if base not in _PRIMITIVES or array is not None:
                raise err(f"constant {cname} must have a primitive scalar type")
            if not value:
                raise err(f"constant {cname} has no value")
            if cname in seen:
                raise err(f"{cname!r} is declared twice")
            seen.add(cname)
            constants.append(MsgConstant(base, cname, _constant_value(base, value, err), lineno))
            continue

        fname = rest.split(None, 1)[0]
        if not _FIELD_NAME.match(fname) or "__" in fname or fname.endswith("_"):
            raise err(f"invalid field name {fname!r}")
        if fname in seen:
            raise err(f"{fname!r} is declared twice")
        seen.add(fname)
        # Default values are not needed on the DDS side (defaults are not on the wire).
        fields.append(MsgField(base, fname, array, size, string_bound, lineno))
    return MsgDef(package, name, fields, constants)


_IDL_PRIMITIVES = {
    "bool": bool,
    "byte": idl.byte,
    # ROS 2 maps `char` to an unsigned 8-bit integer, not to an IDL char.
    "char": idl.uint8,
    "int8": idl.int8,
    "uint8": idl.uint8,
    "int16": idl.int16,
    "uint16": idl.uint16,
    "int32": idl.int32,
    "uint32": idl.uint32,
    "int64": idl.int64,
    "uint64": idl.uint64,
    "float32": idl.float32,
    "float64": idl.float64,
    "string": str,
}
_ZERO = {"bool": False, "string": "", "float32": 0.0, "float64": 0.0}


def _discover(root: Path) -> Dict[str, Tuple[str, str, Path]]:
    """ROS type name -> (package, name, path) for msgs/msg/*.msg and msgs/std/<pkg>/msg/*.msg."""
    found = {}
    for path in sorted((root / "msg").glob("*.msg")):
        found[f"tyre_msgs/msg/{path.stem}"] = ("tyre_msgs", path.stem, path)
    for path in sorted((root / "std").glob("*/msg/*.msg")):
        pkg = path.parent.parent.name
        found[f"{pkg}/msg/{path.stem}"] = (pkg, path.stem, path)
    return found


def load(root: Path = MSGS_DIR) -> Tuple[Dict[str, type], Dict[str, MsgDef]]:
    """Parse every .msg under ``root`` and build the IdlStruct classes.

    Returns ``(types, definitions)``: ``types`` maps ROS 2 names (``std_msgs/msg/Header``) and,
    for tyre_msgs, short names (``RigSample``) to classes; ``definitions`` maps ROS 2 names to
    the parsed files.
    """
    files = _discover(root)
    defs: Dict[str, MsgDef] = {}
    for ros_name, (pkg, name, path) in files.items():
        rel = path.relative_to(root.parent) if root.parent in path.parents else path
        defs[ros_name] = parse_msg(pkg, name, path.read_text(encoding="utf-8"), str(rel))

    built: Dict[str, type] = {}

    def build(ros_name: str, stack: Tuple[str, ...] = ()) -> type:
        if ros_name in built:
            return built[ros_name]
        if ros_name in stack:
            raise MsgDefError(ros_name, 0, "message type contains itself")
        d = defs[ros_name]
        annotations: Dict[str, Any] = {}
        namespace: Dict[str, Any] = {}
        for f in d.fields:
            default: Any
            if f.base in _PRIMITIVES:
                if f.base == "wstring":
                    raise MsgDefError(ros_name, f.line, "wstring is not supported here")
                elem: Any = _IDL_PRIMITIVES[f.base]
                if f.base == "string" and f.string_bound is not None:
                    elem = idl.bounded_str[f.string_bound]
                default = _ZERO.get(f.base, 0)
                factory = None
            else:
                pkg, name = f.base.split("/")
                dep = f"{pkg}/msg/{name}"
                if dep not in defs:
                    raise MsgDefError(ros_name, f.line, f"unknown message type {f.base!r}")
                elem = build(dep, stack + (ros_name,))
                default = dataclasses.MISSING
                factory = elem
            if f.array is None:
                annotations[f.name] = elem
                namespace[f.name] = field(default_factory=factory) if factory else default
            elif f.array == "fixed":
                annotations[f.name] = idl.array[elem, f.size]
                n = f.size
                if factory:
                    namespace[f.name] = field(default_factory=lambda c=factory, n=n: [c() for _ in range(n)])
                else:
                    namespace[f.name] = field(default_factory=lambda v=default, n=n: [v] * n)
            else:
                annotations[f.name] = (
                    idl.sequence[elem, f.size] if f.array == "bounded" else idl.sequence[elem]
                )
                namespace[f.name] = field(default_factory=list)

        def body(ns: Dict[str, Any]) -> None:
            # IdlMeta.__prepare__ already put an __annotations__ dict in the namespace.
            ns["__annotations__"].update(annotations)
            ns.update(namespace)
            ns["__module__"] = __name__
            ns["__doc__"] = f"{d.ros_type_name} (DDS type {d.dds_type_name}), from the .msg file."

        cls = _pytypes.new_class(d.name, (IdlStruct,), {"typename": d.dds_type_name}, body)
        cls = dataclass(cls)
        for c in d.constants:
            setattr(cls, c.name, c.value)
        built[ros_name] = cls
        return cls

    for ros_name in defs:
        build(ros_name)

    table: Dict[str, type] = dict(built)
    for ros_name, cls in built.items():
        if ros_name.startswith("tyre_msgs/msg/"):
            table[ros_name.rsplit("/", 1)[1]] = cls
    return table, defs


#: Classes by ROS 2 name (``tyre_msgs/msg/RigSample``) and, for tyre_msgs, short name.
#: ``definitions``: parsed .msg files by ROS 2 name.
types, definitions = load()
