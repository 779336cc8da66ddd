"""Third-party checks of tyre_msgs' wire format and MCAP schemas.

- Python ``cyclonedds`` (a real DDS implementation) serializes messages built from the .msg files
  (via ``tyre_msgs_idl``) and the bytes must equal, byte for byte, what the Rust side produces
  for the same values (``cargo run -p tyre_msgs --example encode_sample``).
- ``mcap-ros2-support`` must decode the Rust payloads using the Rust side's ``ros2msg`` schema
  text, both directly and from an MCAP file written with the Python ``mcap`` writer.

Run from anywhere with the venv's pytest, e.g.::

    /work/venv-msgs/bin/pytest tests/python -q

``cargo`` must be on PATH; ``CARGO_TARGET_DIR`` is honoured.
"""

from __future__ import annotations

import dataclasses
import functools
import io
import subprocess
import sys
from pathlib import Path
from typing import Any, Dict

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from mcap.reader import make_reader  # noqa: E402
from mcap.writer import Writer  # noqa: E402
from mcap_ros2._dynamic import generate_dynamic  # noqa: E402
from mcap_ros2.decoder import DecoderFactory  # noqa: E402

from tyre_msgs_idl import MsgDefError, definitions, parse_msg, types  # noqa: E402

REPO = Path(__file__).resolve().parents[2]

Header = types["std_msgs/msg/Header"]
Time = types["builtin_interfaces/msg/Time"]
KeyValue = types["diagnostic_msgs/msg/KeyValue"]
DiagnosticStatus = types["diagnostic_msgs/msg/DiagnosticStatus"]
DiagnosticArray = types["diagnostic_msgs/msg/DiagnosticArray"]
Clock = types["rosgraph_msgs/msg/Clock"]


def header(sec: int, nanosec: int, frame_id: str):
    return Header(stamp=Time(sec=sec, nanosec=nanosec), frame_id=frame_id)


# The same values as msgs/examples/encode_sample.rs: change both together.
EXPECTED: Dict[str, Any] = {
    "tyre_msgs/msg/RigSample": types["RigSample"](
        header=header(12, 345_678_901, "iso_w"),
        seq=1_234_567,
        runtime_s=12.345678901,
        fx_n=-1523.25,
        fyw_n=2210.5,
        fzw_n=4000.0,
        mxw_nm=-12.75,
        myw_nm=3.5,
        mzw_nm=-45.125,
        slipangl_deg=-2.5,
        longslip=0.0625,
        inclangl_deg=1.5,
        inflpres_pa=250_000.0,
        trajvelw_mps=16.5,
        wheel_speed_radps=52.25,
        dstwowhc_m=0.3125,
        trdtempi_c=41.5,
        trdtempc_c=43.25,
        trdtempo_c=40.0,
        rig_mode=types["RigSetpoint"].MODE_COUPLED,
        fault_flags=types["RigSample"].FAULT_TEMPERATURE | types["RigSample"].FAULT_ESTOP,
    ),
    "tyre_msgs/msg/RigSetpoint": types["RigSetpoint"](
        header=header(3, 0, "iso_w"),
        seq=99,
        mode=types["RigSetpoint"].MODE_STATIC,
        slip_angle_deg=4.0,
        slip_ratio=-0.125,
        fz_n=3000.0,
        camber_deg=-1.0,
        pressure_pa=180_000.0,
        speed_mps=0.0,
        belt_displacement_m=0.015,
        hold_slip_angle=True,
        hold_slip_ratio=False,
        hold_load=True,
        hold_camber=False,
        sweep_name="FreeRoll_sw14_VariableRate_LR2_HR30_TH4_1",
    ),
    "tyre_msgs/msg/ProcedureCommand": types["ProcedureCommand"](
        header=header(5, 6, ""),
        command=types["ProcedureCommand"].ABORT,
        procedure="gs2mf",
        operator_name="Zoë Ångström",
    ),
    "tyre_msgs/msg/QualityReport": types["QualityReport"](
        header=header(100, 5, ""),
        level=types["QualityCheck"].WARN,
        checks=[
            types["QualityCheck"](
                level=types["QualityCheck"].WARN,
                check="graph_sweep_drift",
                message="Fy-Drift 4,2 % — über Schwelle",
                value=4.25,
                threshold=3.0,
                unit="%",
                rig_time_s=99.5,
            ),
            types["QualityCheck"](
                level=types["QualityCheck"].OK,
                check="wear",
                message="ok ✓",
                value=0.375,
                threshold=2.0,
                unit="mm",
                rig_time_s=100.0,
            ),
        ],
        wear_mm=0.375,
        wear_pct_usable=5.5,
        wear_forecast_mm=1.875,
        tread_depth_new_mm=8.0,
        tread_depth_min_mm=1.5,
    ),
    "diagnostic_msgs/msg/DiagnosticArray": DiagnosticArray(
        header=header(7, 8, "rig"),
        status=[
            DiagnosticStatus(
                level=DiagnosticStatus.WARN,
                name="tyrerig: thermal",
                message="Abkühlung läuft",
                hardware_id="rig-1",
                values=[KeyValue(key="baseline_c", value="45.0"), KeyValue(key="ü", value="✓")],
            ),
            DiagnosticStatus(level=DiagnosticStatus.OK, name="x"),
        ],
    ),
    "rosgraph_msgs/msg/Clock": Clock(clock=Time(sec=1_700_000_000, nanosec=999_999_999)),
}


def cargo_example(*args: str) -> str:
    """Run the Rust example and return its stdout."""
    cmd = ["cargo", "run", "-q", "-p", "tyre_msgs", "--example", "encode_sample", "--", *args]
    done = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True)
    if done.returncode != 0:
        pytest.fail(f"{' '.join(cmd)} failed:\n{done.stderr}")
    return done.stdout


@functools.lru_cache(maxsize=None)
def rust_payloads() -> Dict[str, bytes]:
    out = {}
    for line in cargo_example().splitlines():
        name, hexdata = line.split()
        out[name] = bytes.fromhex(hexdata)
    return out


@functools.lru_cache(maxsize=None)
def rust_schema(type_name: str) -> str:
    return cargo_example("schema", type_name)


def plain(value: Any) -> Any:
    """Dataclasses and mcap_ros2's decoded objects as nested dicts/lists, for comparison."""
    if dataclasses.is_dataclass(value):
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if hasattr(value, "__slots__") and hasattr(value, "_type"):
        return {name: plain(getattr(value, name)) for name in value.__slots__}
    if hasattr(value, "__dict__") and not isinstance(value, type):
        return {k: plain(v) for k, v in vars(value).items() if not k.startswith("_")}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    return value


# --- cyclonedds ---------------------------------------------------------------------------


def test_types_carry_ros2_dds_names_and_constants():
    assert types["RigSample"].__idl_typename__ == "tyre_msgs::msg::dds_::RigSample_"
    assert Header.__idl_typename__ == "std_msgs::msg::dds_::Header_"
    assert Time.__idl_typename__ == "builtin_interfaces::msg::dds_::Time_"
    assert types["RigSetpoint"].MODE_SAFE == 3
    assert DiagnosticStatus.STALE == 3
    assert types["ProcedureState"].PHASE_TYRE_CHANGE == 9
    assert types["RigSample"] is types["tyre_msgs/msg/RigSample"]
    # Every .msg found on disk became a class.
    assert set(definitions) <= set(types)
    assert len(definitions) == 22


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_cyclonedds_round_trip(name):
    msg = EXPECTED[name]
    payload = msg.serialize()
    assert payload[:4] == b"\x00\x01\x00\x00", "expected XCDR1 little-endian encapsulation"
    assert type(msg).deserialize(payload) == msg


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_cyclonedds_bytes_equal_rust_bytes(name):
    rust = rust_payloads()[name]
    python = EXPECTED[name].serialize()
    assert python.hex() == rust.hex()


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_cyclonedds_decodes_rust_bytes(name):
    decoded = type(EXPECTED[name]).deserialize(rust_payloads()[name])
    assert decoded == EXPECTED[name]


def test_rust_example_covers_every_expected_value():
    assert sorted(rust_payloads()) == sorted(EXPECTED)


# --- mcap-ros2-support ----------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_mcap_ros2_decodes_rust_payload_with_rust_schema(name):
    schema = rust_schema(name)
    assert schema.count("=" * 80 + "\nMSG: ") == schema.count("MSG: ")
    decoders = generate_dynamic(name, schema)
    decoded = decoders[name](rust_payloads()[name])
    assert plain(decoded) == plain(EXPECTED[name])


def test_mcap_file_round_trip_with_rust_schemas():
    buf = io.BytesIO()
    writer = Writer(buf)
    writer.start(profile="ros2", library="tyrerig test_idl_roundtrip")
    channels = {}
    for name in sorted(EXPECTED):
        schema_id = writer.register_schema(
            name=name, encoding="ros2msg", data=rust_schema(name).encode("utf-8")
        )
        channels[name] = writer.register_channel(
            topic=f"/test/{name.rsplit('/', 1)[1]}", message_encoding="cdr", schema_id=schema_id
        )
    for i, name in enumerate(sorted(EXPECTED)):
        writer.add_message(
            channel_id=channels[name],
            log_time=1000 + i,
            data=rust_payloads()[name],
            publish_time=1000 + i,
        )
    writer.finish()

    buf.seek(0)
    reader = make_reader(buf, decoder_factories=[DecoderFactory()])
    seen = {}
    for schema, _channel, _message, decoded in reader.iter_decoded_messages():
        seen[schema.name] = plain(decoded)
    assert seen == {name: plain(msg) for name, msg in EXPECTED.items()}


def test_every_embedded_schema_parses_in_mcap_ros2():
    names = cargo_example("types").split()
    assert len(names) == 22
    for name in names:
        decoders = generate_dynamic(name, rust_schema(name))
        assert name in decoders


# --- the Python .msg parser -----------------------------------------------------------------


def test_parser_reports_file_and_line():
    with pytest.raises(MsgDefError) as e:
        parse_msg("tyre_msgs", "Bad", "uint8 ok\nflaot64 x\n", "msg/Bad.msg")
    assert str(e.value).startswith("msg/Bad.msg:2:")
    with pytest.raises(MsgDefError):
        parse_msg("tyre_msgs", "Bad", "uint8 X=256\n", "msg/Bad.msg")


def test_parser_reads_arrays_constants_and_refs():
    d = parse_msg(
        "tyre_msgs",
        "T",
        "std_msgs/Header header # c\nuint8 MODE=3\nQualityCheck[] checks\nfloat64[3] v\n"
        "uint8[<=4] b\nstring<=8 s\n",
    )
    assert [f.name for f in d.fields] == ["header", "checks", "v", "b", "s"]
    assert d.fields[0].base == "std_msgs/Header"
    assert (d.fields[1].base, d.fields[1].array) == ("tyre_msgs/QualityCheck", "unbounded")
    assert (d.fields[2].array, d.fields[2].size) == ("fixed", 3)
    assert (d.fields[3].array, d.fields[3].size) == ("bounded", 4)
    assert d.fields[4].string_bound == 8
    assert d.constants[0].value == 3


def test_msg_files_pass_the_rosidl_adapter_parser():
    """The .msg files parse with (mcap_ros2's copy of) rosidl_adapter's parser, the one colcon
    uses to turn .msg into .idl, and it sees the same fields and constants as tyre_msgs_idl."""
    from mcap_ros2._vendor.rosidl_adapter.parser import parse_message_string

    for ros_name, d in definitions.items():
        pkg, _, name = ros_name.split("/")
        text = (
            (REPO / "msgs" / "msg" / f"{name}.msg")
            if pkg == "tyre_msgs"
            else (REPO / "msgs" / "std" / pkg / "msg" / f"{name}.msg")
        ).read_text(encoding="utf-8")
        spec = parse_message_string(pkg, name, text)
        assert [f.name for f in spec.fields] == [f.name for f in d.fields], ros_name
        assert [c.name for c in spec.constants] == [c.name for c in d.constants], ros_name
        assert [c.value for c in spec.constants] == [c.value for c in d.constants], ros_name
        for theirs, ours in zip(spec.fields, d.fields):
            base = theirs.type.type if theirs.type.pkg_name is None else f"{theirs.type.pkg_name}/{theirs.type.type}"
            assert base == ours.base, (ros_name, ours.name)
            assert theirs.type.is_array == (ours.array is not None), (ros_name, ours.name)
