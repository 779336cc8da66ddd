"""The test_pattern node's content, recomputed from the .msg files (see nodes/test_pattern).

Message number n of a type is filled depth-first over its fields in .msg order with a leaf
counter k: floats n + k/8; unsigned ints (n + k) mod 2**bits; signed (n + k) mod 2**(bits-1);
bool (n + k) odd; string f"{n}:{k}:ü"; an unbounded array has length (n + k) mod 3 (one k)
followed by its elements.
"""

from __future__ import annotations

from typing import Any, Dict

from tyre_msgs_idl import definitions, types

_BITS = {"byte": 8, "char": 8, "uint8": 8, "uint16": 16, "uint32": 32, "uint64": 64,
         "int8": 8, "int16": 16, "int32": 32, "int64": 64}


def _fill(ros_name: str, n: int, k: list) -> Any:
    d = definitions[ros_name]
    values: Dict[str, Any] = {}
    for f in d.fields:
        if f.array is None:
            values[f.name] = _leaf(f.base, n, k)
        elif f.array == "unbounded":
            length = (n + k[0]) % 3
            k[0] += 1
            values[f.name] = [_leaf(f.base, n, k) for _ in range(length)]
        else:
            raise ValueError(f"{ros_name}.{f.name}: fixed/bounded arrays are not in the pattern")
    return types[ros_name](**values)


def _leaf(base: str, n: int, k: list) -> Any:
    if "/" in base:
        pkg, name = base.split("/")
        return _fill(f"{pkg}/msg/{name}", n, k)
    v = n + k[0]
    kk = k[0]
    k[0] += 1
    if base in ("float64", "float32"):
        return n + kk / 8.0
    if base == "bool":
        return v % 2 == 1
    if base == "string":
        return f"{n}:{kk}:ü"
    bits = _BITS[base]
    return v % (2 ** (bits - 1)) if base.startswith("int") else v % (2 ** bits)


def expected(ros_name: str, n: int) -> Any:
    """Message n of the pattern for a type named like ``tyre_msgs/msg/RigSample``."""
    return _fill(ros_name, n, [0])


def plain(obj: Any) -> Any:
    """Nested dicts/lists/primitives of any decoded message (cyclonedds or mcap_ros2 object)."""
    if isinstance(obj, (list, tuple)):
        return [plain(x) for x in obj]
    if isinstance(obj, (bool, int, float, str)) or obj is None:
        return obj
    if hasattr(obj, "__dataclass_fields__"):
        return {name: plain(getattr(obj, name)) for name in obj.__dataclass_fields__}
    if hasattr(obj, "__slots__"):
        return {name: plain(getattr(obj, name)) for name in obj.__slots__}
    return {name: plain(v) for name, v in vars(obj).items() if not name.startswith("_")}


def stamp_sec(obj: Any) -> int:
    """n of a pattern message: the first leaf, its stamp's seconds."""
    if hasattr(obj, "header"):
        return obj.header.stamp.sec
    return obj.clock.sec
