"""MATLAB files from an independent writer and reader (scipy.io): `.mat` files written by
``scipy.io.savemat`` in every form it has (Level 5 plain and compressed, Level 4, channels as
variables or in a struct, column or row vectors, integer classes) read by ``tyrerig inspect
--json`` with every sweep found; and `.mat` files written by ``tyrerig export mat`` read back by
``scipy.io.loadmat`` with the values of the `.dat` they came from."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
import scipy.io

RATE = 50.0
LOADS = [1100.0, 660.0, 1540.0]


def run_channels() -> dict[str, np.ndarray]:
    """A small TTC-like cornering run in SAE axes and TTC units: standstill, then a 12 s sweep
    0 → -12° → +12° → 0 at each of three loads with ramps between, then standstill."""
    t_parts, v, fz, sa = [], [], [], []

    def seg(n, vv, ff, ss):
        v.extend(vv if hasattr(vv, "__len__") else [vv] * n)
        fz.extend(ff if hasattr(ff, "__len__") else [ff] * n)
        sa.extend(ss if hasattr(ss, "__len__") else [ss] * n)

    seg(100, 0.0, 220.0, 0.0)
    seg(150, list(np.linspace(0, 40, 150)), 220.0, 0.0)
    last = 220.0
    for load in LOADS:
        seg(100, 40.0, list(np.linspace(last, load, 100)), 0.0)
        seg(75, 40.0, load, 0.0)
        f = np.linspace(0, 1, 600)
        tri = np.where(f < 0.25, -4 * f, np.where(f < 0.75, -1 + 4 * (f - 0.25), 1 - 4 * (f - 0.75)))
        seg(600, 40.0, load, list(12.0 * tri))
        seg(50, 40.0, load, 0.0)
        last = load
    seg(100, 40.0, list(np.linspace(last, 220.0, 100)), 0.0)
    seg(150, list(np.linspace(40, 0, 150)), 220.0, 0.0)
    seg(100, 0.0, 220.0, 0.0)
    n = len(v)
    rng = np.random.default_rng(3)
    fz = np.array(fz) + rng.normal(0, 5, n)
    sa = np.array(sa) + rng.normal(0, 0.02, n)
    alpha = np.radians(-sa)
    fy_iso = -2.3 * fz * np.sin(1.4 * np.arctan(9 * alpha))
    return {
        "ET": np.arange(n) / RATE,
        "V": np.array(v),
        "SA": sa,
        "IA": np.zeros(n),
        "P": np.full(n, 83.0) + rng.normal(0, 0.2, n),
        "FX": rng.normal(0, 5, n),
        "FY": -fy_iso,
        "FZ": -fz,
        "MZ": 0.02 * fy_iso,
        "SL": np.zeros(n),
        "SR": np.where(np.array(v) > 1, -0.01 + rng.normal(0, 0.006, n), -0.9),
        "TSTC": np.full(n, 50.0),
    }


TIREID = "Hoosier 20.5x7.0-13 R25B on 7 in. wide rim -- Tire 15"
TESTID = "Cornering, Various pressures"


def inspect(tyrerig: Path, path: Path) -> dict:
    out = subprocess.run([str(tyrerig), "inspect", "--json", str(path)], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)["files"][0]


def check(report: dict, rows: int):
    assert report["rows"] == rows
    assert report["tire_id"] == TIREID
    assert report["convention"] == "SAE"
    sweeps = [s for s in report["sweeps"] if not s["conditioning"]]
    assert [s["kind"] for s in sweeps] == ["cornering"] * 3, report["sweeps"]
    for s, load in zip(sweeps, LOADS):
        assert abs(s["fz_n"] - load) < 20, s
        assert abs(s["p_kpa"] - 83.0) < 1, s
        assert abs(s["reach"] - 12.0) < 0.3, s
    reasons = dict(report["excluded"])
    assert reasons.get("standstill (V ≈ 0)", 0) > 0 and reasons.get("load ramp", 0) > 0, reasons


@pytest.mark.parametrize(
    "form",
    ["v5", "v5-compressed", "v5-rows", "v5-struct", "v5-int-classes", "v4"],
)
def test_scipy_written_mat_reads_with_every_sweep(tyrerig, tmp_path: Path, form: str):
    ch = run_channels()
    rows = len(ch["ET"])
    path = tmp_path / f"{form}.mat"
    ids = {"tireid": TIREID, "testid": TESTID}
    if form == "v5":
        scipy.io.savemat(path, {**ch, **ids})
    elif form == "v5-compressed":
        scipy.io.savemat(path, {**ch, **ids}, do_compression=True)
    elif form == "v5-rows":
        scipy.io.savemat(path, {**ch, **ids}, oned_as="row")
    elif form == "v5-struct":
        scipy.io.savemat(path, {"run": ch, **ids}, do_compression=True)
    elif form == "v5-int-classes":
        # Channels stored in integer and single classes, as some exporters do.
        ch2 = dict(ch)
        ch2["IA"] = ch["IA"].astype(np.int8)
        ch2["P"] = np.round(ch["P"]).astype(np.uint16)
        ch2["FZ"] = np.round(ch["FZ"]).astype(np.int32)
        ch2["TSTC"] = ch["TSTC"].astype(np.float32)
        scipy.io.savemat(path, {**ch2, **ids})
    else:
        scipy.io.savemat(path, {**ch, **ids}, format="4")
    report = inspect(tyrerig, path)
    check(report, rows)
    if form == "v5-struct":
        assert "struct variable `run`" in report["layout"]


def test_tyrerig_written_mat_reads_in_scipy(tyrerig, tmp_path: Path):
    ch = run_channels()
    dat = tmp_path / "run.dat"
    names = list(ch)
    units = {"ET": "s", "V": "kph", "SA": "deg", "IA": "deg", "P": "kPa", "FX": "N", "FY": "N", "FZ": "N", "MZ": "N-m", "SL": "none", "SR": "none", "TSTC": "degC"}
    lines = [f"TIRF Data File: scipy check; Tire_Name={TIREID}", "\t".join(names), "\t".join(units[n] for n in names)]
    for i in range(len(ch["ET"])):
        lines.append("\t".join(f"{ch[n][i]:.6f}" for n in names))
    dat.write_text("\r\n".join(lines) + "\r\n")
    check(inspect(tyrerig, dat), len(ch["ET"]))
    for extra, key in [([], None), (["--uncompressed"], None), (["--struct", "run"], "run"), (["--big-endian"], None)]:
        out = tmp_path / f"out{len(extra)}{key}.mat"
        subprocess.run([str(tyrerig), "export", "mat", str(dat), "--out", str(out), *extra], check=True)
        m = scipy.io.loadmat(out)
        src = m[key][0, 0] if key else m
        for n in names:
            got = np.asarray(src[n]).ravel()
            assert got.shape == ch[n].shape, n
            assert np.allclose(got, ch[n], atol=1e-6, rtol=0), n
        assert str(m["tireid"][0]) == TIREID
        check(inspect(tyrerig, out), len(ch["ET"]))
