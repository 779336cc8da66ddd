//! A virtual rig run written as a Calspan TIRF / FSAE TTC run file would be, quirks included.
//!
//! The readers of this crate are tested against files made here: the virtual rig's run (its
//! `RigSample` and `ProcedureState` streams, from an MCAP log or handed over directly) becomes
//! a [`ChannelTable`] with the TTC channels, units and SAE signs, and everything real files
//! carry besides clean sweeps (`docs/ttc-export.md`, `../shared/real-rig-data.md`):
//!
//! * channels `ET V N SA IA RL RE P FX FY FZ MX MZ NFX NFY RST TSTI TSTC TSTO AMBTMP SR SL` in
//!   kph, rpm, deg, cm, kPa (or psi), N (or lbf), N-m, degC;
//! * SAE signs: FY, FZ, SA and MZ change sign from ISO-W (FZ is negative under load); FX, MX,
//!   IA and SL keep theirs;
//! * 50 Hz (block means of the rig's samples; 100 Hz on request);
//! * a title line `TIRF Data File: Project …; Run …; …; Tire_Name=…; Rim_Width=…`, a `tireid`
//!   and a `testid` (the procedure's title), either of which can be dropped;
//! * `SL`: the rig's slip ratio (what it controls in coupled mode), exactly 0 whenever the drive
//!   is not coupled (free rolling, standstill, cornering);
//! * `SR`: the rig's own slip from its reference radius, SR = N·R_ref/V − 1, with R_ref a fixed
//!   value about 1 % below the tyre's free-rolling radius and a noisy wheel-speed encoder: in a
//!   cornering run it is non-zero (median ≈ −0.01) and noisy; at standstill, where the formula
//!   divides by nothing, the rig writes about −0.9;
//! * `RE` = V/N from the same noisy encoder: nonsense near standstill;
//! * `AMBTMP` written in degF under a `degC` label; `RST` the belt temperature;
//! * the standstill at the start and end, load and pressure ramps, settles and conditioning
//!   sweeps all left in (real files have them);
//! * options to drop `testid`, `NFX` or `SL`.
//!
//! Text output: [`to_dat_compact`] (the `.dat` layout with each channel at the rig's
//! resolution, shortest form), or [`crate::table::to_dat`]. A `.mat` writer takes the same
//! [`ChannelTable`] (its `tire_id` and `test_id` become the `tireid` and `testid` strings).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use mcaplog::LogReader;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tyre_msgs::{ProcedureState, RigSample, RigSetpoint, RosMessage};

use crate::table::{ChannelTable, Column};

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The log could not be read or decoded.
    #[error("{path}: {detail}")]
    Log {
        /// The log.
        path: String,
        /// What went wrong.
        detail: String,
    },
    /// The run has nothing to export.
    #[error("{0}")]
    Empty(String),
    /// An option is out of range.
    #[error("option `{key}`: {reason}")]
    Option {
        /// The option.
        key: &'static str,
        /// Why.
        reason: String,
    },
}

/// A virtual rig run: what the exporter needs from a log.
#[derive(Debug, Clone, Default)]
pub struct VirtualRun {
    /// Where it came from (a log path).
    pub source: String,
    /// The rig's samples in time order (ISO-W, SI, as published).
    pub samples: Vec<RigSample>,
    /// The sequencer's states in time order.
    pub states: Vec<ProcedureState>,
    /// The log's metadata records (`tyre`, `procedure`, `rig`, …).
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
}

impl VirtualRun {
    /// Reads the `RigSample` and `ProcedureState` topics and the metadata of an MCAP log.
    pub fn from_log(path: &Path) -> Result<VirtualRun, ExportError> {
        let err = |detail: String| ExportError::Log { path: path.display().to_string(), detail };
        let reader = LogReader::open(path).map_err(|e| err(e.to_string()))?;
        let topic_of = |ty: String| reader.topics().into_iter().find(|t| t.ros_type == ty).map(|t| t.topic);
        let sample_topic = topic_of(RigSample::ros_type_name()).ok_or_else(|| err("no RigSample topic".into()))?;
        let samples = reader.typed::<RigSample>(&sample_topic).map_err(|e| err(e.to_string()))?;
        let states = match topic_of(ProcedureState::ros_type_name()) {
            Some(t) => reader.typed::<ProcedureState>(&t).map_err(|e| err(e.to_string()))?,
            None => Vec::new(),
        };
        let mut samples: Vec<RigSample> = samples.into_iter().map(|(_, s)| s).collect();
        samples.sort_by(|a, b| a.runtime_s.total_cmp(&b.runtime_s));
        Ok(VirtualRun {
            source: path.display().to_string(),
            samples,
            states: states.into_iter().map(|(_, s)| s).collect(),
            metadata: reader.metadata().clone(),
        })
    }

    fn meta(&self, record: &str, key: &str) -> Option<&str> {
        self.metadata.get(record).and_then(|m| m.get(key)).map(String::as_str)
    }
}

/// Pressure unit of the `P` channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PressureUnit {
    /// kPa (most TTC rounds).
    #[default]
    Kpa,
    /// psi (some files).
    Psi,
}

/// Force unit of `FX`, `FY`, `FZ`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ForceUnit {
    /// newton.
    #[default]
    N,
    /// pound-force (some files).
    Lbf,
}

/// How the units line is spelled: test rounds differ (`../shared/real-rig-data.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum UnitSpelling {
    /// `s kph rpm deg cm kPa N N-m none degC` (AMBTMP °F under a `degC` label).
    #[default]
    Ttc,
    /// A later round: `sec`, `Nm`, `deg C`, AMBTMP honestly `deg F`, SL `SAE`.
    LaterRound,
    /// US units: V in mph, RL and RE in in, P in psi, forces in lbf, temperatures in degF.
    Us,
}

/// How to write the run.
#[derive(Debug, Clone, PartialEq)]
pub struct TtcExportOptions {
    /// Spelling (and for US units, the values) of the units line.
    pub units: UnitSpelling,
    /// Output rate [Hz]: 50 (older rounds) or 100; must divide the log's sample rate.
    pub rate_hz: u32,
    /// Unit of `P`.
    pub pressure_unit: PressureUnit,
    /// Unit of the forces.
    pub force_unit: ForceUnit,
    /// Write `testid` (the procedure's title).
    pub with_test_id: bool,
    /// Write the `NFX` channel.
    pub with_nfx: bool,
    /// Write the `SL` channel.
    pub with_sl: bool,
    /// Project number of the title line.
    pub project: u32,
    /// Run number of the title line.
    pub run: u32,
    /// Tyre specimen number (`-- Tire 15` in `tireid`).
    pub tire_number: u32,
    /// Tyre name (default: the log's `tyre.name`, else its file).
    pub tire_name: Option<String>,
    /// Rim width [in] (default: the log's `tyre.rim_width_in`, else 7.0).
    pub rim_width_in: Option<f64>,
    /// `testid` (default: the log's procedure title).
    pub test_id: Option<String>,
    /// The rig's reference radius sits this fraction below the tyre's median free-rolling
    /// radius (what makes `SR` ≈ −0.01 in cornering) [-].
    pub sr_reference_bias: f64,
    /// Relative 1σ noise of the rig's wheel-speed encoder (`N`, hence `SR`, `RE`) [-].
    pub wheel_speed_noise: f64,
    /// Seed of the exporter's own noise (encoder, ambient and road temperature sensors).
    pub seed: u64,
}

impl Default for TtcExportOptions {
    fn default() -> Self {
        Self {
            units: UnitSpelling::Ttc,
            rate_hz: 50,
            pressure_unit: PressureUnit::Kpa,
            force_unit: ForceUnit::N,
            with_test_id: true,
            with_nfx: true,
            with_sl: true,
            project: 2356,
            run: 4,
            tire_number: 1,
            tire_name: None,
            rim_width_in: None,
            test_id: None,
            sr_reference_bias: 0.01,
            wheel_speed_noise: 0.003,
            seed: 0,
        }
    }
}

/// Below this belt speed the rig's slip and radius formulas divide by (almost) nothing [m/s].
const STANDSTILL_MPS: f64 = 0.15;
/// What real files show for `SR` at standstill.
const STANDSTILL_SR: f64 = -0.9;
/// Noise on the standstill `SR` value [-].
const STANDSTILL_SR_NOISE: f64 = 0.02;
/// Wheel-speed encoder noise floor [rad/s] (what it reads on a wheel at rest).
const WHEEL_SPEED_FLOOR_RADPS: f64 = 0.005;
/// Ambient and road temperature sensor noise (1σ) [K].
const TEMPERATURE_NOISE_K: f64 = 0.15;
/// N per lbf.
const N_PER_LBF: f64 = 4.448_221_615_260_5;
/// kPa per psi.
const KPA_PER_PSI: f64 = 6.894_757_293_168_36;

/// Deterministic N(0, 1) draws (Box–Muller on ChaCha8).
struct Noise(ChaCha8Rng);

impl Noise {
    fn normal(&mut self) -> f64 {
        let u1 = ((self.0.next_u64() >> 11) as f64 + 1.0) / 9_007_199_254_740_992.0;
        let u2 = (self.0.next_u64() >> 11) as f64 / 9_007_199_254_740_992.0;
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// One output row before unit conversion (block mean of the rig's samples, ISO-W, SI).
#[derive(Debug, Clone, Copy, Default)]
struct Row {
    t: f64,
    v: f64,
    omega: f64,
    sa: f64,
    ia: f64,
    rl: f64,
    p: f64,
    fx: f64,
    fy: f64,
    fz: f64,
    mx: f64,
    mz: f64,
    ti: f64,
    tc: f64,
    to: f64,
    /// The rig's slip ratio while coupled, 0 otherwise.
    sl: f64,
}

/// The span of samples the procedure ran over: from its first non-idle state to its end
/// (complete, aborted), so the rig's power-up rows (unloaded, in its safe state) are not
/// written — a real file starts with the tyre loaded at standstill.
fn procedure_span(run: &VirtualRun) -> (f64, f64) {
    let stamp = |s: &ProcedureState| s.header.stamp.as_secs_f64();
    let start = run.states.iter().find(|s| s.phase != ProcedureState::PHASE_IDLE).map(stamp);
    let end = run
        .states
        .iter()
        .find(|s| {
            matches!(
                s.phase,
                ProcedureState::PHASE_COMPLETE | ProcedureState::PHASE_ABORTED | ProcedureState::PHASE_ESTOP
            )
        })
        .map(stamp);
    (start.unwrap_or(f64::NEG_INFINITY), end.unwrap_or(f64::INFINITY))
}

/// Turns a virtual run into a TTC-style channel table.
pub fn export_ttc(run: &VirtualRun, opts: &TtcExportOptions) -> Result<ChannelTable, ExportError> {
    if !(opts.rate_hz == 50 || opts.rate_hz == 100) {
        return Err(ExportError::Option {
            key: "rate_hz",
            reason: format!("expected 50 or 100, got {}", opts.rate_hz),
        });
    }
    if !(opts.sr_reference_bias.is_finite() && opts.sr_reference_bias.abs() < 0.2) {
        return Err(ExportError::Option { key: "sr_reference_bias", reason: "expected |bias| < 0.2".into() });
    }
    if !(opts.wheel_speed_noise.is_finite() && (0.0..0.1).contains(&opts.wheel_speed_noise)) {
        return Err(ExportError::Option { key: "wheel_speed_noise", reason: "expected 0 ≤ noise < 0.1".into() });
    }
    let (t0, t1) = procedure_span(run);
    let samples: Vec<&RigSample> = run.samples.iter().filter(|s| s.runtime_s >= t0 && s.runtime_s <= t1).collect();
    if samples.len() < 2 {
        return Err(ExportError::Empty(format!("{}: fewer than two rig samples while the procedure ran", run.source)));
    }
    let dt_in = (samples[samples.len() - 1].runtime_s - samples[0].runtime_s) / (samples.len() - 1) as f64;
    let per_row = (1.0 / (dt_in * f64::from(opts.rate_hz))).round();
    if per_row.is_nan() || per_row < 1.0 {
        return Err(ExportError::Option {
            key: "rate_hz",
            reason: format!("{} Hz is faster than the log's {:.0} Hz samples", opts.rate_hz, 1.0 / dt_in),
        });
    }
    let rows = block_means(&samples, per_row as usize);

    // The rig's reference radius: a fixed value ~1 % below the tyre's median free-rolling
    // radius (V/Ω over the rolling rows with the drive uncoupled).
    let mut free: Vec<f64> =
        rows.iter().filter(|r| r.v > 2.0 && r.omega > 0.0 && r.sl == 0.0).map(|r| r.v / r.omega).collect();
    free.sort_by(f64::total_cmp);
    let r_free = free.get(free.len() / 2).copied().unwrap_or_else(|| rows.iter().map(|r| r.rl).fold(0.0, f64::max));
    let r_ref = r_free * (1.0 - opts.sr_reference_bias);

    let ambient_c: f64 = run.meta("rig", "ambient_temp_c").and_then(|v| v.parse().ok()).unwrap_or(30.0);
    let road_c: f64 = run.meta("rig", "belt_temp_c").and_then(|v| v.parse().ok()).unwrap_or(ambient_c);
    let mut noise = Noise(ChaCha8Rng::seed_from_u64(opts.seed));
    let (kf, fu) = match opts.force_unit {
        ForceUnit::N => (1.0, "N"),
        ForceUnit::Lbf => (1.0 / N_PER_LBF, "lbf"),
    };
    let (kp, pu) = match opts.pressure_unit {
        PressureUnit::Kpa => (1e-3, "kPa"),
        PressureUnit::Psi => (1e-3 / KPA_PER_PSI, "psi"),
    };
    let n = rows.len();
    let mut ch: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
    let mut put = |name: &'static str, v: f64| ch.entry(name).or_insert_with(|| Vec::with_capacity(n)).push(v);
    let t_start = rows[0].t;
    for r in &rows {
        // The rig's wheel-speed encoder: relative noise plus a floor (a wheel at rest reads a
        // little), which is what SR and RE are computed from.
        let omega =
            r.omega * (1.0 + opts.wheel_speed_noise * noise.normal()) + WHEEL_SPEED_FLOOR_RADPS * noise.normal();
        let standstill = r.v.abs() < STANDSTILL_MPS;
        let sr =
            if standstill { STANDSTILL_SR + STANDSTILL_SR_NOISE * noise.normal() } else { omega * r_ref / r.v - 1.0 };
        let re_cm = if omega.abs() > 1e-9 { (100.0 * r.v / omega).clamp(-9999.0, 9999.0) } else { 0.0 };
        // SAE: FZ negative under load; FY, SA, MZ mirrored.
        let fz_sae = -r.fz;
        let fy_sae = -r.fy;
        let nf = |f: f64| if fz_sae.abs() > 1.0 { f / fz_sae } else { 0.0 };
        put("ET", r.t - t_start);
        put("V", r.v * 3.6);
        put("N", omega * 60.0 / std::f64::consts::TAU);
        put("SA", -r.sa);
        put("IA", r.ia);
        put("RL", 100.0 * r.rl);
        put("RE", re_cm);
        put("P", r.p * kp);
        put("FX", r.fx * kf);
        put("FY", fy_sae * kf);
        put("FZ", fz_sae * kf);
        put("MX", r.mx);
        put("MZ", -r.mz);
        put("NFX", nf(r.fx));
        put("NFY", nf(fy_sae));
        put("RST", road_c + TEMPERATURE_NOISE_K * noise.normal());
        put("TSTI", r.ti);
        put("TSTC", r.tc);
        put("TSTO", r.to);
        // Written in degF under a degC label, as real files do.
        put("AMBTMP", (ambient_c + TEMPERATURE_NOISE_K * noise.normal()) * 9.0 / 5.0 + 32.0);
        put("SR", sr);
        put("SL", r.sl);
    }
    let layout: [(&'static str, &str, bool); 22] = [
        ("ET", "s", true),
        ("V", "kph", true),
        ("N", "rpm", true),
        ("SA", "deg", true),
        ("IA", "deg", true),
        ("RL", "cm", true),
        ("RE", "cm", true),
        ("P", pu, true),
        ("FX", fu, true),
        ("FY", fu, true),
        ("FZ", fu, true),
        ("MX", "N-m", true),
        ("MZ", "N-m", true),
        ("NFX", "none", opts.with_nfx),
        ("NFY", "none", true),
        ("RST", "degC", true),
        ("TSTI", "degC", true),
        ("TSTC", "degC", true),
        ("TSTO", "degC", true),
        ("AMBTMP", "degC", true),
        ("SR", "none", true),
        ("SL", "none", opts.with_sl),
    ];
    let mut columns: Vec<Column> = layout
        .iter()
        .filter(|(_, _, on)| *on)
        .map(|(name, unit, _)| Column {
            name: (*name).to_owned(),
            unit: (*unit).to_owned(),
            values: ch.remove(name).unwrap_or_default(),
        })
        .collect();
    respell(&mut columns, opts.units);

    let tire_name = opts
        .tire_name
        .clone()
        .or_else(|| run.meta("tyre", "name").map(str::to_owned))
        .or_else(|| run.meta("tyre", "file").map(str::to_owned))
        .unwrap_or_else(|| "virtual tyre".to_owned());
    let rim =
        opts.rim_width_in.or_else(|| run.meta("tyre", "rim_width_in").and_then(|v| v.parse().ok())).unwrap_or(7.0);
    let test_id = opts
        .test_id
        .clone()
        .or_else(|| run.meta("procedure", "title").map(str::to_owned))
        .or_else(|| run.meta("procedure", "name").map(str::to_owned))
        .unwrap_or_else(|| "virtual rig run".to_owned());
    let title = format!(
        "TIRF Data File: Project {}; Run {:03}; Test {}; Source tyrerig virtual rig; Tire_Name={}; Rim_Width={:.1}",
        opts.project, opts.run, test_id, tire_name, rim
    );
    Ok(ChannelTable {
        source: run.source.clone(),
        title: Some(title),
        tire_id: Some(format!("{tire_name} on {rim:.1} in. wide rim -- Tire {}", opts.tire_number)),
        test_id: opts.with_test_id.then_some(test_id),
        columns,
    })
}

/// A unit as a round spells it, and the conversion of the values from the TTC unit if any.
type Respelled = (&'static str, Option<fn(f64) -> f64>);

/// Rewrites the units line in a round's spelling; for US units converts the values too.
fn respell(columns: &mut [Column], spelling: UnitSpelling) {
    for c in columns.iter_mut() {
        let (unit, convert): Respelled = match (spelling, c.name.as_str(), c.unit.as_str()) {
            (UnitSpelling::Ttc, ..) => continue,
            (UnitSpelling::LaterRound, "ET", _) => ("sec", None),
            (UnitSpelling::LaterRound, "MX" | "MZ", _) => ("Nm", None),
            (UnitSpelling::LaterRound, "AMBTMP", _) => ("deg F", None),
            (UnitSpelling::LaterRound, _, "degC") => ("deg C", None),
            (UnitSpelling::LaterRound, "SL", _) => ("SAE", None),
            (UnitSpelling::Us, "V", _) => ("mph", Some(|v| v / 1.609_344)),
            (UnitSpelling::Us, "RL" | "RE", _) => ("in", Some(|v| v / 2.54)),
            (UnitSpelling::Us, "P", "kPa") => ("psi", Some(|v| v / KPA_PER_PSI)),
            (UnitSpelling::Us, "FX" | "FY" | "FZ", "N") => ("lbf", Some(|v| v / N_PER_LBF)),
            // AMBTMP is already written in °F.
            (UnitSpelling::Us, "AMBTMP", _) => ("degF", None),
            (UnitSpelling::Us, _, "degC") => ("degF", Some(|v| v * 9.0 / 5.0 + 32.0)),
            _ => continue,
        };
        c.unit = unit.to_owned();
        if let Some(f) = convert {
            c.values.iter_mut().for_each(|v| *v = f(*v));
        }
    }
}

/// Means of `per_row` consecutive samples (the rig's DAQ filters before it decimates).
fn block_means(samples: &[&RigSample], per_row: usize) -> Vec<Row> {
    samples
        .chunks(per_row)
        .filter(|c| c.len() == per_row)
        .map(|c| {
            let k = 1.0 / c.len() as f64;
            let mut r = Row::default();
            for s in c {
                let coupled = s.rig_mode == RigSetpoint::MODE_COUPLED;
                r.t += k * s.runtime_s;
                r.v += k * s.trajvelw_mps;
                r.omega += k * s.wheel_speed_radps;
                r.sa += k * s.slipangl_deg;
                r.ia += k * s.inclangl_deg;
                r.rl += k * s.dstwowhc_m;
                r.p += k * s.inflpres_pa;
                r.fx += k * s.fx_n;
                r.fy += k * s.fyw_n;
                r.fz += k * s.fzw_n;
                r.mx += k * s.mxw_nm;
                r.mz += k * s.mzw_nm;
                r.ti += k * s.trdtempi_c;
                r.tc += k * s.trdtempc_c;
                r.to += k * s.trdtempo_c;
                r.sl += if coupled { k * s.longslip } else { 0.0 };
            }
            r
        })
        .collect()
}

/// Resolution each TTC channel is written at (decimal places), as a rig's DAQ would.
fn decimals(channel: &str) -> usize {
    match channel {
        "ET" => 3,
        "V" | "MX" | "MZ" => 2,
        "N" | "P" | "RE" | "RST" | "TSTI" | "TSTC" | "TSTO" | "AMBTMP" => 1,
        "SA" | "IA" | "RL" => 3,
        "FX" | "FY" | "FZ" => 1,
        "NFX" | "NFY" | "SR" | "SL" => 4,
        _ => 4,
    }
}

/// The TTC `.dat` layout (title, names, units, tab-separated rows, CRLF) with each channel
/// rounded to its resolution and written in its shortest form (`0`, `-12.3`), which keeps a
/// 20,000-row run near 2.5 MB.
pub fn to_dat_compact(table: &ChannelTable) -> String {
    let eol = "\r\n";
    let mut s = String::with_capacity(table.rows() * 24 * table.columns.len().max(1) / 4);
    s.push_str(table.title.as_deref().unwrap_or("tyrerig export"));
    s.push_str(eol);
    s.push_str(&table.columns.iter().map(|c| c.name.as_str()).collect::<Vec<_>>().join("\t"));
    s.push_str(eol);
    s.push_str(&table.columns.iter().map(|c| c.unit.as_str()).collect::<Vec<_>>().join("\t"));
    s.push_str(eol);
    let scale: Vec<f64> = table.columns.iter().map(|c| 10f64.powi(decimals(&c.name) as i32)).collect();
    for row in 0..table.rows() {
        for (i, c) in table.columns.iter().enumerate() {
            if i > 0 {
                s.push('\t');
            }
            let v = c.values.get(row).copied().unwrap_or(f64::NAN);
            if v.is_finite() {
                // `+ 0.0` turns −0 into 0.
                let q = (v * scale[i]).round() / scale[i] + 0.0;
                let _ = write!(s, "{q}");
            } else {
                s.push_str("NaN");
            }
        }
        s.push_str(eol);
    }
    s
}
