//! Measured data: rig samples joined with the sequencer's sweep states, the derived state
//! variables the effect catalogue needs (sliding power and energy, grip temperature, slip
//! rates), and the decimated points residuals are computed at.

use crate::DoctorError;
use crate::flash;
use std::path::Path;
use tyre_msgs::{ProcedureState, RigSample};

/// One log's messages, in time order.
#[derive(Debug, Clone, Default)]
pub struct RawLog {
    /// Where it came from (file name), for messages.
    pub source: String,
    /// `/rig/sample` messages.
    pub samples: Vec<RigSample>,
    /// `/rig/procedure/state` messages.
    pub states: Vec<ProcedureState>,
}

impl RawLog {
    /// Reads the samples and procedure states of an MCAP log.
    pub fn read_mcap(path: &Path) -> Result<Self, DoctorError> {
        let file = path.display().to_string();
        let log = mcaplog::LogReader::open(path)
            .map_err(|e| DoctorError::Log { file: file.clone(), detail: e.to_string() })?;
        let samples = log
            .typed::<RigSample>("/rig/sample")
            .map_err(|e| DoctorError::Log { file: file.clone(), detail: format!("/rig/sample: {e}") })?
            .into_iter()
            .map(|(_, s)| s)
            .collect::<Vec<_>>();
        let states = log
            .typed::<ProcedureState>("/rig/procedure/state")
            .map_err(|e| DoctorError::Log { file: file.clone(), detail: format!("/rig/procedure/state: {e}") })?
            .into_iter()
            .map(|(_, s)| s)
            .collect::<Vec<_>>();
        if samples.is_empty() {
            return Err(DoctorError::NoData { what: format!("{file}: no /rig/sample messages") });
        }
        Ok(Self { source: file, samples, states })
    }
}

/// Options for turning logs into a [`Dataset`].
#[derive(Debug, Clone)]
pub struct DataOptions {
    /// Rate of the points residuals are computed at [Hz] (the full-rate samples are kept for
    /// integrals and filters).
    pub point_rate_hz: f64,
    /// Slowest belt speed whose samples are used [m/s] (step-steer rolls at 1 m/s: relaxation
    /// dominates there and MF's low-speed reductions apply).
    pub min_speed_mps: f64,
    /// Lowest load whose samples are used [N]. Low enough for a TTC run's lightest cell
    /// (220 N, wandering ±20 % in some rounds): a race tyre's drive/brake run repeats a 220 N
    /// cell at its end on the hot tyre, the one revisit of that run (with 300 N here the
    /// doctor never saw it).
    pub min_load_n: f64,
    /// Sliding power below which the lasers read the grip temperature without flash [W].
    pub quiet_power_w: f64,
    /// Window of the input smoother (slip angle, slip ratio, load, camber, pressure, speed) [s];
    /// 0 = raw inputs.
    pub input_smoothing_s: f64,
    /// How long the flash temperature outlives sliding [s] (a few flash time constants).
    pub quiet_memory_s: f64,
    /// Most points kept (evenly thinned beyond it, so a full GS2MF log stays tractable).
    pub max_points: usize,
}

impl Default for DataOptions {
    fn default() -> Self {
        Self {
            point_rate_hz: 10.0,
            min_speed_mps: 3.0,
            min_load_n: 150.0,
            quiet_power_w: 1500.0,
            input_smoothing_s: 0.1,
            quiet_memory_s: 0.5,
            max_points: 8000,
        }
    }
}

/// Sweep bookkeeping.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SweepInfo {
    /// Sweep name from the sequencer (thesis naming).
    pub name: String,
    /// Index of the sweep in its procedure.
    pub index_in_log: u32,
    /// Log it came from.
    pub log: String,
    /// Ordinal over all logs (0, 1, …): the "time in the test" axis.
    pub ordinal: usize,
    /// The sweep was driven in coupled mode (slip-ratio sweep).
    pub coupled: bool,
}

/// The full-rate measured series of every usable sample, plus derived state variables.
#[derive(Debug, Clone, Default)]
pub struct Series {
    /// Rig time [s] (continuous over logs: later logs are offset).
    pub t_s: Vec<f64>,
    /// Sweep ordinal (index into [`Dataset::sweeps`]) or `usize::MAX` between sweeps.
    pub sweep: Vec<usize>,
    /// Start of a new tyre (first sample of a log or after a tyre change): integrals reset.
    pub new_tyre: Vec<bool>,
    /// Ordinal of the tyre (specimen) over the test: 0 for the first log's tyre, one more at
    /// every new tyre.
    pub tyre: Vec<usize>,
    /// SLIPANGL [deg].
    pub alpha_deg: Vec<f64>,
    /// LONGSLIP [-].
    pub kappa: Vec<f64>,
    /// FZW [N].
    pub fz_n: Vec<f64>,
    /// INCLANGL [deg].
    pub gamma_deg: Vec<f64>,
    /// INFLPRES [Pa].
    pub p_pa: Vec<f64>,
    /// TRAJVELW [m/s].
    pub v_mps: Vec<f64>,
    /// Wheel speed [rad/s].
    pub omega_radps: Vec<f64>,
    /// FX [N].
    pub fx_n: Vec<f64>,
    /// FYW [N].
    pub fy_n: Vec<f64>,
    /// MZW [N·m].
    pub mz_nm: Vec<f64>,
    /// DSTWOWHC [m] (NaN when flagged invalid).
    pub rl_m: Vec<f64>,
    /// Mean of the finite ones of TRDTEMPI/C/O as the lasers read it [°C] (NaN when none is).
    pub temp_laser_c: Vec<f64>,
    /// Sliding power √(PX² + PY²) from the measured forces [W].
    pub sliding_power_w: Vec<f64>,
    /// Sliding energy accumulated on this tyre so far [J].
    pub sliding_energy_j: Vec<f64>,
    /// Grip temperature: the laser mean read while sliding is quiet, interpolated through
    /// sliding (the lasers see the flash temperature, which does not set grip) [°C].
    pub temp_grip_c: Vec<f64>,
    /// dα/dt [deg/s] (smoothed).
    pub alpha_rate_dps: Vec<f64>,
    /// dκ/dt [1/s] (smoothed).
    pub kappa_rate_ps: Vec<f64>,
}

impl Series {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Sliding energy above a power threshold accumulated on this tyre [J], per sample.
    pub fn severe_energy_j(&self, threshold_w: f64) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.len());
        let mut e = 0.0;
        for i in 0..self.len() {
            if self.new_tyre[i] {
                e = 0.0;
            } else if i > 0 {
                let dt = (self.t_s[i] - self.t_s[i - 1]).clamp(0.0, 0.1);
                e += (self.sliding_power_w[i] - threshold_w).max(0.0) * dt;
            }
            out.push(e);
        }
        out
    }
}

/// What the doctor fits against: the series, the decimated points in sweeps, and the sweeps.
#[derive(Debug, Clone, Default)]
pub struct Dataset {
    /// Full-rate series.
    pub series: Series,
    /// Indices into the series of the points residuals are computed at.
    pub points: Vec<usize>,
    /// The sweeps, by ordinal.
    pub sweeps: Vec<SweepInfo>,
    /// Sources, for the report.
    pub sources: Vec<String>,
    /// Per log (tyre), the time constant of the laser flash's decay after sliding, fitted from
    /// its quiet stretches [s]; `None` when no decay shows (its quiet laser readings are used as
    /// they are).
    pub flash_decay_s: Vec<Option<f64>>,
}

fn finite_or_nan(v: f64) -> f64 {
    if v.is_finite() { v } else { f64::NAN }
}

impl Dataset {
    /// Builds the dataset from logs (in test order: a later log continues the test on the
    /// tyre of the earlier one only if it does not start with a tyre change; each log starts a
    /// new tyre for the integrals, as each log is one specimen's run).
    pub fn from_logs(logs: &[RawLog], opt: &DataOptions) -> Result<Self, DoctorError> {
        let mut ds = Dataset::default();
        let mut t_offset = 0.0;
        for log in logs {
            ds.append_log(log, opt, &mut t_offset)?;
        }
        if ds.points.is_empty() {
            return Err(DoctorError::NoData {
                what: format!(
                    "{}: no samples inside sweeps (PHASE_SWEEP) above {} m/s",
                    ds.sources.join(", "),
                    opt.min_speed_mps
                ),
            });
        }
        if ds.points.len() > opt.max_points.max(100) {
            let step = ds.points.len().div_ceil(opt.max_points.max(100));
            ds.points = ds.points.iter().copied().step_by(step).collect();
        }
        ds.derive(opt);
        Ok(ds)
    }

    fn append_log(&mut self, log: &RawLog, opt: &DataOptions, t_offset: &mut f64) -> Result<(), DoctorError> {
        self.sources.push(log.source.clone());
        let s = &mut self.series;
        let mut st_i = 0usize;
        let mut cur: Option<&ProcedureState> = None;
        let mut last_sweep_key: Option<(u32, String)> = None;
        let mut cur_ordinal = usize::MAX;
        let mut first = true;
        let mut last_t = f64::NEG_INFINITY;
        let dt_pub = {
            let n = log.samples.len().min(200);
            if n >= 2 { (log.samples[n - 1].runtime_s - log.samples[0].runtime_s) / (n - 1) as f64 } else { 0.01 }
        };
        let stride = ((1.0 / opt.point_rate_hz) / dt_pub.max(1e-4)).round().max(1.0) as usize;
        let mut since_point = 0usize;
        let mut tyre_change_pending = false;
        let mut outside_change_seen = false;
        for smp in &log.samples {
            let t = smp.runtime_s;
            if !t.is_finite() || t <= last_t {
                continue;
            }
            last_t = t;
            while st_i < log.states.len() && stamp_s(&log.states[st_i]) <= t + 1e-9 {
                cur = Some(&log.states[st_i]);
                st_i += 1;
            }
            // A tyre is mounted where a tyre change ends: the samples of the change itself (the
            // rig parked) are the old tyre's, and the change a log opens with mounts its first
            // tyre. Marking every sample of a change as a new tyre counted a 900 s change as
            // ninety thousand tyres, and no specimen term could be fitted.
            let in_change = cur.is_some_and(|st| st.phase == ProcedureState::PHASE_TYRE_CHANGE);
            if in_change && outside_change_seen {
                tyre_change_pending = true;
            }
            let in_sweep = cur.is_some_and(|st| st.phase == ProcedureState::PHASE_SWEEP);
            if smp.fault_flags & (RigSample::FAULT_FORCE | RigSample::FAULT_ESTOP) != 0 {
                continue;
            }
            let sweep = if in_sweep {
                let st = cur.expect("in_sweep implies a state");
                let key = (st.sweep_index, st.sweep_name.clone());
                if last_sweep_key.as_ref() != Some(&key) {
                    cur_ordinal = self.sweeps.len();
                    self.sweeps.push(SweepInfo {
                        name: st.sweep_name.clone(),
                        index_in_log: st.sweep_index,
                        log: log.source.clone(),
                        ordinal: cur_ordinal,
                        coupled: false,
                    });
                    last_sweep_key = Some(key);
                    since_point = 0;
                }
                if smp.rig_mode == tyre_msgs::RigSetpoint::MODE_COUPLED {
                    self.sweeps[cur_ordinal].coupled = true;
                }
                cur_ordinal
            } else {
                last_sweep_key = None;
                usize::MAX
            };
            let idx = s.t_s.len();
            s.t_s.push(t + *t_offset);
            s.sweep.push(sweep);
            s.new_tyre.push(first || (tyre_change_pending && !in_change));
            first = false;
            if !in_change {
                tyre_change_pending = false;
                outside_change_seen = true;
            }
            s.alpha_deg.push(smp.slipangl_deg);
            s.kappa.push(smp.longslip);
            s.fz_n.push(smp.fzw_n);
            s.gamma_deg.push(smp.inclangl_deg);
            s.p_pa.push(smp.inflpres_pa);
            s.v_mps.push(smp.trajvelw_mps);
            s.omega_radps.push(smp.wheel_speed_radps);
            s.fx_n.push(smp.fx_n);
            s.fy_n.push(smp.fyw_n);
            s.mz_nm.push(smp.mzw_nm);
            s.rl_m.push(if smp.fault_flags & RigSample::FAULT_RADIUS != 0 {
                f64::NAN
            } else {
                finite_or_nan(smp.dstwowhc_m)
            });
            let temp = if smp.fault_flags & RigSample::FAULT_TEMPERATURE != 0 {
                f64::NAN
            } else {
                // The mean of the tread channels the rig has (a rig may log only the centre).
                let (sum, n) = [smp.trdtempi_c, smp.trdtempc_c, smp.trdtempo_c]
                    .iter()
                    .filter(|t| t.is_finite())
                    .fold((0.0, 0usize), |(s, n), t| (s + t, n + 1));
                if n == 0 { f64::NAN } else { sum / n as f64 }
            };
            s.temp_laser_c.push(temp);
            let usable = sweep != usize::MAX
                && smp.trajvelw_mps >= opt.min_speed_mps
                && smp.fzw_n >= opt.min_load_n
                && smp.rig_mode != tyre_msgs::RigSetpoint::MODE_STATIC
                && [smp.slipangl_deg, smp.longslip, smp.fx_n, smp.fyw_n, smp.mzw_nm].iter().all(|v| v.is_finite());
            if sweep != usize::MAX {
                if usable && since_point.is_multiple_of(stride) {
                    self.points.push(idx);
                }
                since_point += 1;
            }
        }
        // The next log's clock starts again near zero: continue after this one.
        *t_offset = self.series.t_s.last().copied().unwrap_or(0.0) + 1.0;
        Ok(())
    }

    /// Input smoothing, sliding power and energy, grip temperature, slip rates.
    fn derive(&mut self, opt: &DataOptions) {
        let s = &mut self.series;
        let n = s.len();
        // Errors in variables: the model is evaluated at the measured inputs, whose sensor noise
        // (0.01° of slip angle is ~20 N of FY near zero slip; 0.0003 of slip ratio ~50 N of FX)
        // would otherwise pass through the model into the residual, and any candidate that
        // low-passes an input (relaxation) would "explain" it. A quadratic Savitzky–Golay
        // smoother over ~0.1 s removes most of it without biasing ramps or rounded peaks.
        if opt.input_smoothing_s > 0.0 {
            let t = s.t_s.clone();
            for v in [&mut s.alpha_deg, &mut s.kappa, &mut s.fz_n, &mut s.gamma_deg, &mut s.p_pa, &mut s.v_mps] {
                *v = savitzky_golay2(&t, v, opt.input_smoothing_s);
            }
        }
        s.sliding_power_w = (0..n)
            .map(|i| {
                let (sa, ca) = s.alpha_deg[i].to_radians().sin_cos();
                let v = s.v_mps[i].max(0.0);
                let py = s.fy_n[i] * v * sa;
                let px = s.fx_n[i] * s.kappa[i] * v * ca;
                (px * px + py * py).sqrt()
            })
            .collect();
        let mut tyre = 0usize;
        s.tyre = (0..n)
            .map(|i| {
                if s.new_tyre[i] && i > 0 {
                    tyre += 1;
                }
                tyre
            })
            .collect();
        let mut e = 0.0;
        s.sliding_energy_j = (0..n)
            .map(|i| {
                if s.new_tyre[i] {
                    e = 0.0;
                } else {
                    let dt = (s.t_s[i] - s.t_s[i - 1]).clamp(0.0, 0.1);
                    e += s.sliding_power_w[i] * dt;
                }
                e
            })
            .collect();
        // Grip temperature: laser mean at quiet moments, linearly interpolated in time through
        // sliding, then a 0.5 s low-pass against laser noise. The flash temperature the lasers
        // see outlives the sliding by a few tenths of a second (longer in the rolling direction),
        // so "quiet" means the sliding power low-passed over `quiet_memory_s` is low — a fast
        // sweep's zero crossing is not quiet.
        let mut p_lp = 0.0;
        let power_lp: Vec<f64> = (0..n)
            .map(|i| {
                let dt = if i > 0 { (s.t_s[i] - s.t_s[i - 1]).clamp(0.0, 1.0) } else { 0.0 };
                // Peak-following low-pass: rises at once, decays with the flash memory.
                p_lp = s.sliding_power_w[i].max(p_lp * (-dt / opt.quiet_memory_s).exp());
                p_lp
            })
            .collect();
        // The flash outlives the quiet memory when sliding was longitudinal (its patch cools
        // over seconds) and a test plan leaves only short pauses between sweeps: the lasers then
        // read tens of kelvin of flash at every "quiet" moment. Its decay is fitted out.
        let (anchors, flash_decay_s) =
            flash::deflashed(&s.t_s, &s.temp_laser_c, &s.sliding_power_w, &power_lp, opt.quiet_power_w, &s.new_tyre);
        let mut tg = vec![f64::NAN; n];
        if !anchors.is_empty() {
            let mut q = 0usize;
            for (i, out) in tg.iter_mut().enumerate() {
                while q + 1 < anchors.len() && anchors[q + 1].0 <= i {
                    q += 1;
                }
                let (a, ta) = anchors[q];
                *out = if i <= a || q + 1 >= anchors.len() {
                    ta
                } else {
                    let (b, tb) = anchors[q + 1];
                    let w = (s.t_s[i] - s.t_s[a]) / (s.t_s[b] - s.t_s[a]).max(1e-9);
                    ta + w * (tb - ta)
                };
            }
            let mut y = tg[0];
            for (i, v) in tg.iter_mut().enumerate() {
                let dt = if i > 0 { (s.t_s[i] - s.t_s[i - 1]).clamp(0.0, 1.0) } else { 0.0 };
                let a = (dt / 0.5).min(1.0);
                y += a * (*v - y);
                *v = y;
            }
        }
        s.temp_grip_c = tg;
        s.alpha_rate_dps = central_rate(&s.t_s, &s.alpha_deg, 0.1);
        s.kappa_rate_ps = central_rate(&s.t_s, &s.kappa, 0.1);
        self.flash_decay_s = flash_decay_s;
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True without points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Sweep ordinal of point `k`.
    pub fn point_sweep(&self, k: usize) -> usize {
        self.series.sweep[self.points[k]]
    }

    /// True when the data has slip-ratio (coupled) sweeps.
    pub fn has_longitudinal(&self) -> bool {
        self.points.iter().any(|&i| self.series.kappa[i].abs() > 0.02)
    }

    /// True when the data has slip-angle sweeps.
    pub fn has_lateral(&self) -> bool {
        self.points.iter().any(|&i| self.series.alpha_deg[i].abs() > 2.0)
    }

    /// Range (max − min) of a per-sample variable over the points.
    pub fn point_range(&self, v: &[f64]) -> f64 {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &i in &self.points {
            if v[i].is_finite() {
                lo = lo.min(v[i]);
                hi = hi.max(v[i]);
            }
        }
        if hi >= lo { hi - lo } else { 0.0 }
    }
}

/// Quadratic Savitzky–Golay smoothing over a centred window of about `window_s`, only where the
/// whole window is evenly sampled (gaps and ends keep the raw value). Exact for quadratics.
fn savitzky_golay2(t: &[f64], y: &[f64], window_s: f64) -> Vec<f64> {
    let n = y.len();
    if n < 5 {
        return y.to_vec();
    }
    let dt = {
        let mut d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).filter(|d| *d > 0.0).take(1000).collect();
        d.sort_by(f64::total_cmp);
        if d.is_empty() {
            return y.to_vec();
        }
        d[d.len() / 2]
    };
    let m = ((window_s / 2.0 / dt).round() as usize).clamp(2, 50);
    let mf = m as f64;
    let den = (2.0 * mf + 3.0) * (2.0 * mf + 1.0) * (2.0 * mf - 1.0);
    let c: Vec<f64> = (0..=m).map(|i| 3.0 * (3.0 * mf * mf + 3.0 * mf - 1.0 - 5.0 * (i * i) as f64) / den).collect();
    let mut out = y.to_vec();
    for i in m..n.saturating_sub(m) {
        let span = t[i + m] - t[i - m];
        if (span - 2.0 * mf * dt).abs() > 0.5 * dt || !(i - m..=i + m).all(|j| y[j].is_finite()) {
            continue;
        }
        let mut acc = c[0] * y[i];
        for k in 1..=m {
            acc += c[k] * (y[i - k] + y[i + k]);
        }
        out[i] = acc;
    }
    out
}

fn stamp_s(st: &ProcedureState) -> f64 {
    f64::from(st.header.stamp.sec) + f64::from(st.header.stamp.nanosec) * 1e-9
}

/// Slope over a ±`half_window_s` window (a least-noisy derivative for slip rates).
fn central_rate(t: &[f64], y: &[f64], half_window_s: f64) -> Vec<f64> {
    let n = t.len();
    let mut out = vec![0.0; n];
    let (mut lo, mut hi) = (0usize, 0usize);
    for i in 0..n {
        while t[i] - t[lo] > half_window_s {
            lo += 1;
        }
        while hi + 1 < n && t[hi + 1] - t[i] <= half_window_s {
            hi += 1;
        }
        let dt = t[hi] - t[lo];
        out[i] = if dt > 1e-6 { (y[hi] - y[lo]) / dt } else { 0.0 };
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state_at(t_s: f64, phase: u8, sweep_index: u32) -> ProcedureState {
        ProcedureState {
            header: tyre_msgs::std_msgs::Header::iso_w(t_s),
            phase,
            sweep_index,
            sweep_name: format!("sweep{sweep_index}"),
            ..Default::default()
        }
    }

    /// A log that opens with the first mounting and changes the tyre once: two tyres, the
    /// second mounted where its change ends, and the sliding energy counted per tyre.
    #[test]
    fn a_tyre_change_mounts_one_new_tyre_where_it_ends() {
        let samples: Vec<RigSample> = (0..60)
            .map(|k| RigSample {
                seq: k,
                runtime_s: k as f64 * 0.1,
                trajvelw_mps: 10.0,
                fzw_n: 4000.0,
                fyw_n: 1000.0,
                slipangl_deg: 3.0,
                inflpres_pa: 2.4e5,
                ..Default::default()
            })
            .collect();
        let states = vec![
            state_at(0.0, ProcedureState::PHASE_TYRE_CHANGE, 0),
            state_at(1.0, ProcedureState::PHASE_SWEEP, 1),
            state_at(3.0, ProcedureState::PHASE_TYRE_CHANGE, 2),
            state_at(4.0, ProcedureState::PHASE_SWEEP, 3),
        ];
        let log = RawLog { source: "two_tyres.mcap".into(), samples, states };
        let ds = Dataset::from_logs(&[log], &DataOptions { input_smoothing_s: 0.0, ..DataOptions::default() })
            .expect("dataset");
        let s = &ds.series;
        let mounted: Vec<usize> = (0..s.len()).filter(|&i| s.new_tyre[i]).collect();
        assert_eq!(mounted, vec![0, 40], "new tyre at the log's start and where the change ends");
        assert_eq!(s.tyre.iter().max(), Some(&1), "two tyres");
        assert_eq!(s.tyre[39], 0, "the change's own samples are the old tyre's");
        assert_eq!(s.sliding_energy_j[40], 0.0, "the new tyre has slid nothing");
        assert!(s.sliding_energy_j[39] > 0.0);
    }
}
