"""A secured third-party DDS peer: Eclipse Cyclone DDS's C library with its DDS Security plugins
(Debian's ``libddsc0debian``, built with security; the PyPI cyclonedds wheel ships no plugins).

``build(workdir)`` writes the IDL of RigSample and ProcedureCommand from the .msg files (the
single source of truth, through ``tyre_msgs_idl.definitions``), compiles it with Cyclone's
``idlc``, generates a JSON printer for every field of RigSample, and links ``cyclone_peer.c``
against ``libddsc``. The program:

    peer read <enclave_dir|-> <count> <timeout_s>      RigSamples from rt/rig/sample as JSON lines
    peer command <enclave_dir|-> <count> <operator>     ProcedureCommand ABORTs on rt/rig/procedure/command

``-`` instead of an enclave directory makes a plain (unsecured) participant. The domain is
``ROS_DOMAIN_ID``. Exit codes: 0 done, 2 timed out, 3 the writer was refused (access control),
4 the participant was refused (security configuration), 1 other errors.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path
from typing import Dict, List

from tyre_msgs_idl import MsgDef, definitions

HERE = Path(__file__).resolve().parent
#: Where Debian's libddsc0debian puts the DDS Security plugins.
PLUGIN_DIR = Path("/usr/lib/x86_64-linux-gnu/libddsc0debian")
PLUGINS = ("libdds_security_auth.so", "libdds_security_ac.so", "libdds_security_crypto.so")

_IDL = {
    "bool": "boolean", "byte": "octet", "char": "uint8", "int8": "int8", "uint8": "uint8",
    "int16": "short", "uint16": "unsigned short", "int32": "long", "uint32": "unsigned long",
    "int64": "long long", "uint64": "unsigned long long", "float32": "float", "float64": "double",
    "string": "string",
}
# printf conversions for the C members idlc generates.
_FMT = {
    "bool": ("%s", "{v} ? \"true\" : \"false\""), "byte": ("%u", "(unsigned){v}"),
    "char": ("%u", "(unsigned){v}"), "uint8": ("%u", "(unsigned){v}"), "int8": ("%d", "(int){v}"),
    "int16": ("%d", "(int){v}"), "uint16": ("%u", "(unsigned){v}"), "int32": ("%d", "(int){v}"),
    "uint32": ("%u", "(unsigned){v}"), "int64": ("%lld", "(long long){v}"),
    "uint64": ("%llu", "(unsigned long long){v}"), "float32": ("%.17g", "(double){v}"),
    "float64": ("%.17g", "{v}"),
}


class PeerUnavailable(RuntimeError):
    """The Debian Cyclone DDS packages the secured-peer tests need are not installed."""


def _ros(base: str) -> str:
    pkg, name = base.split("/")
    return f"{pkg}/msg/{name}"


def _order(roots: List[str]) -> List[MsgDef]:
    """The definitions ``roots`` need, dependencies first."""
    out: List[MsgDef] = []
    seen = set()

    def visit(name: str) -> None:
        if name in seen:
            return
        seen.add(name)
        for f in definitions[name].fields:
            if "/" in f.base:
                visit(_ros(f.base))
        out.append(definitions[name])

    for r in roots:
        visit(r)
    return out


def idl_text(roots: List[str]) -> str:
    """IDL with the ROS 2 DDS type names (``module tyre_msgs { module msg { module dds_ {``)."""
    lines = []
    for d in _order(roots):
        members = []
        for f in d.fields:
            if "/" in f.base:
                pkg, name = f.base.split("/")
                t = f"::{pkg}::msg::dds_::{name}_"
            elif f.base == "string" and f.string_bound is not None:
                t = f"string<{f.string_bound}>"
            else:
                t = _IDL[f.base]
            if f.array is None:
                members.append(f"{t} {f.name};")
            elif f.array == "fixed":
                members.append(f"{t} {f.name}[{f.size}];")
            elif f.array == "bounded":
                members.append(f"sequence<{t}, {f.size}> {f.name};")
            else:
                members.append(f"sequence<{t}> {f.name};")
        body = " ".join(members)
        lines.append(
            f"module {d.package} {{ module msg {{ module dds_ {{ "
            f"@final struct {d.name}_ {{ {body} }}; }}; }}; }};"
        )
    return "\n".join(lines) + "\n"


def _c_type(ros_name: str) -> str:
    d = definitions[ros_name]
    return f"{d.package}_msg_dds__{d.name}_"


def printer_c(ros_name: str) -> str:
    """C that prints one message as a JSON object of all its (scalar and nested) fields."""
    out: List[str] = []

    def emit(name: str, expr: str, first: List[bool]) -> None:
        d = definitions[name]
        for f in d.fields:
            if f.array is not None:
                raise ValueError(f"{name}.{f.name}: arrays are not printed")
            sep = "" if first[0] else ","
            first[0] = False
            v = f"{expr}.{f.name}"
            if "/" in f.base:
                out.append(f'  fputs("{sep}\\"{f.name}\\":{{", stdout);')
                emit(_ros(f.base), v, [True])
                out.append('  fputs("}", stdout);')
            elif f.base == "string":
                out.append(f'  printf("{sep}\\"{f.name}\\":"); print_json_string({v});')
            else:
                fmt, arg = _FMT[f.base]
                if f.base == "bool":
                    out.append(f'  printf("{sep}\\"{f.name}\\":%s", {arg.format(v=v)});')
                else:
                    out.append(f'  printf("{sep}\\"{f.name}\\":{fmt}", {arg.format(v=v)});')

    emit(ros_name, "(*m)", [True])
    c_type = _c_type(ros_name)
    return (
        f"static void print_{definitions[ros_name].name}(const {c_type} *m) {{\n"
        '  fputs("{", stdout);\n' + "\n".join(out) + '\n  fputs("}\\n", stdout);\n  fflush(stdout);\n}\n'
    )


def build(workdir: Path) -> Path:
    """Compiles the peer in ``workdir``; returns the executable."""
    missing = [t for t in ("idlc", "gcc") if shutil.which(t) is None]
    missing += [str(PLUGIN_DIR / p) for p in PLUGINS if not (PLUGIN_DIR / p).exists()]
    if missing or not Path("/usr/include/dds/dds.h").exists():
        raise PeerUnavailable(
            "the secured Cyclone DDS peer needs Debian's cyclonedds-dev, cyclonedds-tools and "
            f"libddsc0debian (apt-get install them; .ci/run does): missing {missing or ['dds/dds.h']}"
        )
    workdir.mkdir(parents=True, exist_ok=True)
    roots = ["tyre_msgs/msg/RigSample", "tyre_msgs/msg/ProcedureCommand"]
    (workdir / "tyre_msgs.idl").write_text(idl_text(roots))
    subprocess.run(["idlc", "-l", "c", "tyre_msgs.idl"], cwd=workdir, check=True, capture_output=True)
    (workdir / "printers.h").write_text(printer_c("tyre_msgs/msg/RigSample"))
    exe = workdir / "cyclone_peer"
    subprocess.run(
        ["gcc", "-O1", "-Wall", "-Werror", "-o", str(exe), "-I", str(workdir),
         f'-DPLUGIN_DIR="{PLUGIN_DIR}"', str(HERE / "cyclone_peer.c"), "tyre_msgs.c", "-lddsc"],
        cwd=workdir, check=True, capture_output=True, text=True,
    )
    return exe


def enclave_env(domain_id: int) -> Dict[str, str]:
    """Environment for the peer: the domain, nothing else of the caller's DDS settings."""
    return {"ROS_DOMAIN_ID": str(domain_id), "PATH": "/usr/bin:/bin"}
