//! How sure the fitted model is of what it predicts: the delta method on the stages' parameter
//! covariances, over a fixed operating-envelope grid.
//!
//! For a model output y(x; p) and parameter covariance Σ, Var y(x) ≈ gᵀ Σ g with g = ∂y/∂p at
//! the fitted p (central differences, steps scaled to each coefficient as in the fit's
//! Jacobian). The stages are fitted one after another, each on its own data, so their
//! covariances are taken as independent (block-diagonal Σ): FY pure uses `fy_pure`'s, FX pure
//! `fx_pure`'s, MZ pure `fy_pure`'s and `mz_pure`'s (the aligning moment is trail × Fy plus the
//! residual torque).
//!
//! That is the uncertainty of the model's *mean* prediction. A new measurement at x also carries
//! the rig's noise and whatever the model cannot represent, estimated by the stage's residual
//! RMSE: the 95 % band for a new measured point is ±1.96·√(σ_model² + RMSE²).

use mftyre::MfInput;

use crate::engine::{BatchScratch, Channel, InputColumns, values_of};
use crate::stages::FitResult;

/// The operating-envelope grid the prediction uncertainty is mapped on. Fixed for a run (it
/// comes from the run's nominal load and pressure, not from the data so far), so successive
/// maps of a live fit compare point by point.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvelopeGrid {
    /// Vertical loads, N.
    pub fz_n: Vec<f64>,
    /// Slip angles of the FY and MZ maps, deg.
    pub slip_angle_deg: Vec<f64>,
    /// Slip ratios of the FX map.
    pub slip_ratio: Vec<f64>,
    /// Cambers, deg.
    pub camber_deg: Vec<f64>,
    /// Inflation pressures, Pa.
    pub pressure_pa: Vec<f64>,
    /// Speed of every grid point, m/s.
    pub speed_mps: f64,
}

impl EnvelopeGrid {
    /// Load fractions of Fz0.
    pub const LOAD_FRACTIONS: [f64; 4] = [0.5, 1.0, 1.5, 2.0];
    /// Slip angles, deg (dense near zero, where the cornering stiffness lives).
    pub const SLIP_ANGLES_DEG: [f64; 11] = [-12.0, -8.0, -4.0, -2.0, -1.0, 0.0, 1.0, 2.0, 4.0, 8.0, 12.0];
    /// Slip ratios.
    pub const SLIP_RATIOS: [f64; 11] = [-0.2, -0.1, -0.05, -0.02, -0.01, 0.0, 0.01, 0.02, 0.05, 0.1, 0.2];
    /// Cambers, deg.
    pub const CAMBERS_DEG: [f64; 5] = [-4.0, -2.0, 0.0, 2.0, 4.0];
    /// Pressure fractions of the nominal pressure.
    pub const PRESSURE_FRACTIONS: [f64; 3] = [0.85, 1.0, 1.15];

    /// The standard grid for a tyre of nominal load `fz0_n`, pressure `p0_pa`, speed `v0_mps`:
    /// load {0.5, 1, 1.5, 2}·Fz0 × slip (11 values) × camber {−4, −2, 0, 2, 4}° × pressure
    /// {0.85, 1, 1.15}·P0 = 660 points per channel.
    pub fn standard(fz0_n: f64, p0_pa: f64, v0_mps: f64) -> Self {
        EnvelopeGrid {
            fz_n: Self::LOAD_FRACTIONS.iter().map(|f| f * fz0_n).collect(),
            slip_angle_deg: Self::SLIP_ANGLES_DEG.to_vec(),
            slip_ratio: Self::SLIP_RATIOS.to_vec(),
            camber_deg: Self::CAMBERS_DEG.to_vec(),
            pressure_pa: Self::PRESSURE_FRACTIONS.iter().map(|f| f * p0_pa).collect(),
            speed_mps: v0_mps,
        }
    }

    /// Points per map (load × slip × camber × pressure).
    pub fn len(&self) -> usize {
        self.fz_n.len()
            * self.slip_angle_deg.len().max(self.slip_ratio.len())
            * self.camber_deg.len()
            * self.pressure_pa.len()
    }

    /// True for a grid without points.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The model inputs of `channel`'s map, load slowest, then slip, camber, pressure fastest.
    pub fn inputs(&self, channel: MapChannel, r0_m: f64) -> Vec<MfInput> {
        let slips: &[f64] = match channel {
            MapChannel::FxPure => &self.slip_ratio,
            MapChannel::FyPure | MapChannel::MzPure => &self.slip_angle_deg,
        };
        let mut out =
            Vec::with_capacity(self.fz_n.len() * slips.len() * self.camber_deg.len() * self.pressure_pa.len());
        for &fz in &self.fz_n {
            for &slip in slips {
                for &camber in &self.camber_deg {
                    for &p in &self.pressure_pa {
                        let (kappa, alpha_rad) = match channel {
                            MapChannel::FxPure => (slip, 0.0),
                            _ => (0.0, slip.to_radians()),
                        };
                        out.push(MfInput {
                            fz_n: fz,
                            kappa,
                            alpha_rad,
                            gamma_rad: camber.to_radians(),
                            phit_per_m: 0.0,
                            vx_mps: self.speed_mps,
                            p_pa: p,
                            omega_radps: self.speed_mps * (1.0 + kappa) / r0_m.max(0.1),
                        });
                    }
                }
            }
        }
        out
    }
}

/// The channels with an uncertainty map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapChannel {
    /// Pure lateral force over slip angle (κ = 0).
    FyPure,
    /// Pure longitudinal force over slip ratio (α = 0).
    FxPure,
    /// Pure aligning moment over slip angle (κ = 0).
    MzPure,
}

impl MapChannel {
    /// Every mapped channel.
    pub const ALL: [MapChannel; 3] = [MapChannel::FyPure, MapChannel::FxPure, MapChannel::MzPure];

    /// The model channel evaluated.
    pub fn channel(self) -> Channel {
        match self {
            MapChannel::FyPure => Channel::Fy0,
            MapChannel::FxPure => Channel::Fx0,
            MapChannel::MzPure => Channel::Mz0,
        }
    }

    /// TYDEX name of the channel (`FYW`, `FX`, `MZW`).
    pub fn tydex_name(self) -> &'static str {
        match self {
            MapChannel::FyPure => "FYW",
            MapChannel::FxPure => "FX",
            MapChannel::MzPure => "MZW",
        }
    }

    /// The stages whose coefficients the channel depends on (their covariances, block-diagonal).
    pub fn stages(self) -> &'static [&'static str] {
        match self {
            MapChannel::FyPure => &["fy_pure"],
            MapChannel::FxPure => &["fx_pure"],
            MapChannel::MzPure => &["fy_pure", "mz_pure"],
        }
    }

    /// The stage whose residual RMSE stands for the noise of a new measurement.
    pub fn residual_stage(self) -> &'static str {
        match self {
            MapChannel::FyPure => "fy_pure",
            MapChannel::FxPure => "fx_pure",
            MapChannel::MzPure => "mz_pure",
        }
    }
}

/// One channel's map over the grid.
#[derive(Debug, Clone, PartialEq)]
pub struct PredictionMap {
    /// The channel.
    pub channel: MapChannel,
    /// Model value at each grid point ([`EnvelopeGrid::inputs`] order).
    pub value: Vec<f64>,
    /// 1σ of the model's mean prediction, every source counted: √(σ_param² + σ_form²). NaN
    /// where a stage it depends on is not fitted.
    pub std: Vec<f64>,
    /// The part of it from the fitted coefficients' covariance (delta method): repeatability
    /// under a correct model.
    pub std_param: Vec<f64>,
    /// The part from the form error, what the model misses systematically where the data are
    /// ([`crate::form_error`]); outside the tested envelope the channel's largest in-envelope
    /// value (the data say nothing there; the worst seen is the honest guess).
    pub std_form: Vec<f64>,
    /// True at grid points outside the tested envelope (no data point within the
    /// [`crate::accuracy::Support`] box): the value there is extrapolated.
    pub extrapolated: Vec<bool>,
    /// The residual RMSE of the channel's stage (NaN before it is fitted).
    pub residual_rmse: f64,
    /// The band for a repeat measurement, channel units: ± this holds 95 % of the stage's
    /// held-out residuals (each sweep's as a fit without it leaves it: the linearised
    /// leave-one-sweep-out of [`crate::form_error::held_out_values`]), at the split-conformal
    /// rank of [`crate::stages::crossval::repeat_band`]. One width over the map; NaN before
    /// the stage is fitted.
    pub repeat_band: f64,
}

impl PredictionMap {
    /// A map of `channel` with `value` but no uncertainty yet (NaN σ, nothing extrapolated).
    fn unfitted(channel: MapChannel, value: Vec<f64>) -> Self {
        let n = value.len();
        PredictionMap {
            channel,
            value,
            std: vec![f64::NAN; n],
            std_param: vec![f64::NAN; n],
            std_form: vec![f64::NAN; n],
            extrapolated: vec![false; n],
            residual_rmse: f64::NAN,
            repeat_band: f64::NAN,
        }
    }
}

/// What the held-out residuals of a map's stage give: the form error at every grid input, which
/// inputs are extrapolated, and the band for a repeat measurement.
struct HeldOutMap {
    std_form: Vec<f64>,
    extrapolated: Vec<bool>,
    repeat_band: f64,
}

/// The form error of `channel` at every one of `inputs` ([`crate::form_error`]) from its
/// residual stage's points, which inputs are extrapolated, and the stage's band for a repeat
/// measurement; `None` without that stage's data.
fn form_errors(result: &FitResult, channel: MapChannel, inputs: &[MfInput], threads: usize) -> Option<HeldOutMap> {
    use crate::form_error::{FormError, SlipAxis};
    let d = result.data.iter().find(|d| d.stage == channel.residual_stage())?;
    let fitted = d.channel.values_at(&result.params, &d.points);
    // Held-out residuals, not in-sample ones: they carry the error where no sweep ran.
    let values = match result.stages.iter().find(|s| s.stage == d.stage && s.skipped.is_none()) {
        Some(rep) => {
            let jacobian = jacobian_at(result, d, &rep.primary_keys, &fitted, threads);
            crate::form_error::held_out_values(&d.points, &d.groups, &fitted, &jacobian)
        }
        None => fitted,
    };
    let axis = match channel {
        MapChannel::FxPure => SlipAxis::Ratio,
        MapChannel::FyPure | MapChannel::MzPure => SlipAxis::Angle,
    };
    let regions = FormError::of(&d.points, &d.groups, &values, axis, result.nominal.fz0_n).over(inputs);
    let worst = regions.iter().filter(|r| r.tested).filter_map(|r| r.std).fold(0.0, f64::max);
    let std_form = regions.iter().map(|r| if r.tested { r.std.unwrap_or(worst) } else { worst }).collect();
    let held_out_errors = values.iter().zip(&d.points).map(|(v, p)| (v - p.measured).abs()).collect();
    Some(HeldOutMap {
        std_form,
        extrapolated: regions.iter().map(|r| !r.tested).collect(),
        repeat_band: crate::stages::crossval::repeat_band(held_out_errors),
    })
}

/// ∂value/∂key of the stage's channel at its points (`fitted`: its values there), one row per
/// key: forward differences (half the model runs of central ones; the held-out shift they feed
/// needs no more than a few digits) with [`ChannelCovariance::step`], the keys spread over
/// `threads`, the points laid out once.
fn jacobian_at(
    result: &FitResult,
    d: &crate::stages::StageData,
    keys: &[&'static str],
    fitted: &[f64],
    threads: usize,
) -> Vec<Vec<f64>> {
    let n = d.points.len();
    let columns = InputColumns::of(&d.points);
    let mut rows = vec![Vec::new(); keys.len()];
    let per_thread = keys.len().div_ceil(threads.max(1)).max(1);
    std::thread::scope(|s| {
        for (t, chunk) in rows.chunks_mut(per_thread).enumerate() {
            let columns = &columns;
            s.spawn(move || {
                let mut p = result.params.clone();
                let mut scratch = BatchScratch::default();
                let mut up = vec![0.0; n];
                for (r, row) in chunk.iter_mut().enumerate() {
                    let key = keys[t * per_thread + r];
                    let Some(v) = p.get(key).filter(|v| v.is_finite()) else {
                        *row = vec![f64::NAN; n];
                        continue;
                    };
                    let h = ChannelCovariance::step(v);
                    let _ = p.set(key, v + h);
                    d.channel.eval_batch(&p, &columns.batch(0..n), &mut scratch, &mut up);
                    let _ = p.set(key, v);
                    *row = up.iter().zip(fitted).map(|(u, f)| (u - f) / h).collect();
                }
            });
        }
    });
    rows
}

/// The parameter covariance one channel's predictions depend on.
#[derive(Debug, Clone)]
pub struct ChannelCovariance {
    keys: Vec<&'static str>,
    /// Row-major, block-diagonal over the stages.
    cov: Vec<f64>,
    residual_rmse: f64,
}

impl ChannelCovariance {
    /// The covariance of `channel`'s coefficients in `result`; `None` while a stage it depends on
    /// has not been fitted (or its covariance could not be computed).
    pub fn of(result: &FitResult, channel: MapChannel) -> Option<Self> {
        let mut blocks = Vec::new();
        for name in channel.stages() {
            let rep = result.stages.iter().find(|s| s.stage == *name && s.skipped.is_none())?;
            let n = rep.primary_keys.len();
            if n == 0 || rep.covariance.len() != n * n {
                return None;
            }
            blocks.push((rep.primary_keys.clone(), rep.covariance.clone()));
        }
        let total: usize = blocks.iter().map(|b| b.0.len()).sum();
        let mut keys = Vec::with_capacity(total);
        let mut cov = vec![0.0; total * total];
        let mut at = 0;
        for (k, c) in blocks {
            let n = k.len();
            for i in 0..n {
                for j in 0..n {
                    cov[(at + i) * total + at + j] = c[i * n + j];
                }
            }
            keys.extend(k);
            at += n;
        }
        let residual_rmse =
            result.stages.iter().find(|s| s.stage == channel.residual_stage()).map_or(f64::NAN, |s| s.rmse);
        Some(ChannelCovariance { keys, cov, residual_rmse })
    }

    /// The residual RMSE of the channel's stage.
    pub fn residual_rmse(&self) -> f64 {
        self.residual_rmse
    }

    /// 1σ of `channel`'s model prediction at `input` for the fitted `params` (delta method).
    pub fn std_at(&self, result: &FitResult, channel: MapChannel, input: &MfInput) -> f64 {
        let base = values_of(&result.params, &self.keys);
        let mut scratch = result.params.clone();
        self.std_with(&mut scratch, &base, channel, input)
    }

    /// [`ChannelCovariance::std_at`] on a scratch copy of the fitted parameters (`base`: the
    /// fitted values of the covariance's keys), left as it was found: no copy per point.
    fn std_with(&self, p: &mut mftyre::TyreParams, base: &[f64], channel: MapChannel, input: &MfInput) -> f64 {
        let ch = channel.channel();
        let n = self.keys.len();
        let mut g = vec![0.0; n];
        for (i, key) in self.keys.iter().enumerate() {
            let h = Self::step(base[i]);
            let _ = p.set(key, base[i] + h);
            let up = ch.eval(p, input);
            let _ = p.set(key, base[i] - h);
            let down = ch.eval(p, input);
            let _ = p.set(key, base[i]);
            g[i] = (up - down) / (2.0 * h);
        }
        self.std_of_gradient(&g)
    }

    /// √(gᵀ Σ g) for the gradient `g` of a prediction with respect to the keys.
    fn std_of_gradient(&self, g: &[f64]) -> f64 {
        let n = self.keys.len();
        let mut var = 0.0;
        for (a, &ga) in g.iter().enumerate().filter(|(_, v)| **v != 0.0) {
            for (b, &gb) in g.iter().enumerate().filter(|(_, v)| **v != 0.0) {
                var += ga * self.cov[a * n + b] * gb;
            }
        }
        var.max(0.0).sqrt()
    }

    /// The central-difference step of a key at fitted value `v`.
    fn step(v: f64) -> f64 {
        1e-6 * v.abs().max(1e-3)
    }

    /// σ at every point of `grid`, on `threads` threads: per coefficient, the channel over the
    /// whole grid at ±h by the batch kernel (each point is 2 model runs per key: the maps are
    /// the live fit's second biggest cost after the stages), then gᵀ Σ g per point.
    fn stds(&self, result: &FitResult, channel: MapChannel, grid: &GridBatch, threads: usize) -> Vec<f64> {
        let ch = channel.channel();
        let base = values_of(&result.params, &self.keys);
        let n_keys = self.keys.len();
        let n = grid.len();
        // g[key][point] = ∂y/∂key at the point.
        let mut g = vec![vec![0.0; n]; n_keys];
        let per_thread = n_keys.div_ceil(threads.max(1)).max(1);
        std::thread::scope(|s| {
            for (t, rows) in g.chunks_mut(per_thread).enumerate() {
                let base = &base;
                s.spawn(move || {
                    let mut p = result.params.clone();
                    let mut scratch = BatchScratch::default();
                    let (mut up, mut down) = (vec![0.0; n], vec![0.0; n]);
                    for (r, row) in rows.iter_mut().enumerate() {
                        let i = t * per_thread + r;
                        let key = self.keys[i];
                        let h = Self::step(base[i]);
                        let _ = p.set(key, base[i] + h);
                        grid.eval(ch, &p, &mut scratch, &mut up);
                        let _ = p.set(key, base[i] - h);
                        grid.eval(ch, &p, &mut scratch, &mut down);
                        let _ = p.set(key, base[i]);
                        for (o, (u, d)) in row.iter_mut().zip(up.iter().zip(&down)) {
                            *o = (u - d) / (2.0 * h);
                        }
                    }
                });
            }
        });
        (0..n).map(|x| self.std_of_gradient(&g.iter().map(|row| row[x]).collect::<Vec<_>>())).collect()
    }

    /// True when `other` is the same covariance of the same keys at the same fitted values.
    fn same_as(&self, other: &ChannelCovariance, result: &FitResult, other_result: &FitResult) -> bool {
        self.keys == other.keys
            && self.cov == other.cov
            && self.residual_rmse.to_bits() == other.residual_rmse.to_bits()
            && values_of(&result.params, &self.keys) == values_of(&other_result.params, &other.keys)
    }
}

/// A grid's points for the batch kernel, ordered so that each load case (load, camber,
/// pressure) is one run of points: the kernel computes a load case's terms once per run.
#[derive(Debug)]
struct GridBatch {
    columns: InputColumns,
    /// `order[k]`: the grid index of the k-th point of `columns`.
    order: Vec<usize>,
}

impl GridBatch {
    fn of(inputs: &[MfInput]) -> Self {
        let mut order: Vec<usize> = (0..inputs.len()).collect();
        let case = |i: &MfInput| [i.fz_n, i.gamma_rad, i.p_pa];
        order.sort_by(|&a, &b| {
            let (x, y) = (case(&inputs[a]), case(&inputs[b]));
            x[0].total_cmp(&y[0]).then(x[1].total_cmp(&y[1])).then(x[2].total_cmp(&y[2]))
        });
        let sorted: Vec<MfInput> = order.iter().map(|&i| inputs[i]).collect();
        GridBatch { columns: InputColumns::of_inputs(&sorted), order }
    }

    fn len(&self) -> usize {
        self.order.len()
    }

    /// `channel` at every grid point, into `out` in grid order.
    fn eval(&self, channel: Channel, params: &mftyre::TyreParams, scratch: &mut BatchScratch, out: &mut [f64]) {
        let n = self.len();
        let mut sorted = vec![0.0; n];
        channel.eval_batch(params, &self.columns.batch(0..n), scratch, &mut sorted);
        for (v, &i) in sorted.iter().zip(&self.order) {
            out[i] = *v;
        }
    }
}

/// Every channel's map over `grid` for the fit `result`.
pub fn prediction_maps(result: &FitResult, grid: &EnvelopeGrid) -> Vec<PredictionMap> {
    prediction_maps_since(result, grid, None, 1)
}

/// [`prediction_maps`] on `threads` threads, taking over a channel's σ from the maps of a
/// `previous` fit (with its maps) where nothing the σ depends on changed: the same keys, values
/// and covariance, and the same model values at every grid point. A live update after a sweep
/// that moved no stage of a channel (a slip-ratio sweep for FY) then costs 660 model runs for
/// that channel instead of 660 × 2 × keys.
pub fn prediction_maps_since(
    result: &FitResult,
    grid: &EnvelopeGrid,
    previous: Option<(&FitResult, &[PredictionMap])>,
    threads: usize,
) -> Vec<PredictionMap> {
    MapChannel::ALL
        .iter()
        .map(|&channel| {
            let inputs = grid.inputs(channel, result.nominal.r0_m);
            let batch = GridBatch::of(&inputs);
            let mut value = vec![0.0; inputs.len()];
            batch.eval(channel.channel(), &result.params, &mut BatchScratch::default(), &mut value);
            let Some(c) = ChannelCovariance::of(result, channel) else {
                return PredictionMap::unfitted(channel, value);
            };
            // The same covariance (bit for bit: the same Jacobian and residual variance, so the
            // same points and residuals) and the same values: the previous map stands, form
            // error included.
            let unchanged = previous.and_then(|(prev, maps)| {
                let m = maps.iter().find(|m| m.channel == channel)?;
                let pc = ChannelCovariance::of(prev, channel)?;
                let same = c.same_as(&pc, result, prev)
                    && m.value.len() == value.len()
                    && m.value.iter().zip(&value).all(|(a, b)| a.to_bits() == b.to_bits());
                same.then(|| m.clone())
            });
            if let Some(m) = unchanged {
                return m;
            }
            let std_param = c.stds(result, channel, &batch, threads);
            let held_out = form_errors(result, channel, &inputs, threads).unwrap_or_else(|| HeldOutMap {
                std_form: vec![0.0; inputs.len()],
                extrapolated: vec![false; inputs.len()],
                repeat_band: f64::NAN,
            });
            let HeldOutMap { std_form, extrapolated, repeat_band } = held_out;
            let std = std_param.iter().zip(&std_form).map(|(a, b)| a.hypot(*b)).collect();
            PredictionMap {
                channel,
                value,
                std,
                std_param,
                std_form,
                extrapolated,
                residual_rmse: c.residual_rmse(),
                repeat_band,
            }
        })
        .collect()
}

/// How often the predicted 95 % bands hold what they claim, for one channel, on points the
/// fit never saw ([`coverage`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Coverage {
    /// The channel (`FYW`, `FX`, `MZW`).
    pub channel: String,
    /// Held-out points scored.
    pub points: usize,
    /// % of measured values inside ±1.96·√(σ_model² + RMSE²) (the band for a new measurement).
    pub measured_in_band_pct: f64,
    /// The band for a repeat measurement ([`PredictionMap::repeat_band`]), channel units.
    pub repeat_band: f64,
    /// % of measured values inside ±`repeat_band` (predicted: 95 %).
    pub measured_in_repeat_band_pct: f64,
    /// % of the reference model's values inside ±1.96·σ_model (the band of the mean), when a
    /// reference (the virtual rig's true tyre) is given.
    pub truth_in_band_pct: Option<f64>,
    /// Median σ_model over the points, channel units.
    pub median_std: f64,
    /// The residual RMSE used.
    pub residual_rmse: f64,
}

/// Scores the predicted bands of `result` on `other` (data the fit never saw, e.g. a repeat
/// run): per mapped channel, the same selection of points its stage makes from `other`.
pub fn coverage(
    result: &FitResult,
    other: &crate::Dataset,
    opts: &crate::FitOptions,
    truth: Option<&crate::accuracy::ReferenceTyre<'_>>,
) -> Vec<Coverage> {
    use crate::stages::{Ctx, STAGES};
    let ctx = Ctx {
        data: other,
        opts,
        nominal: result.nominal.clone(),
        settings: crate::fit::StepSettings::default(),
        grid: crate::physics::Grid::of_range(&result.params, &result.range),
        resampled: crate::stages::context::Resampled::of(other),
    };
    let mut out = Vec::new();
    for channel in MapChannel::ALL {
        let Some(cov) = ChannelCovariance::of(result, channel) else { continue };
        let Some(stage) = STAGES.iter().find(|s| s.name() == channel.residual_stage()) else { continue };
        let Some(sel) = stage.select(&ctx) else { continue };
        let ch = channel.channel();
        let repeat_band = form_errors(result, channel, &[], 1).map_or(f64::NAN, |h| h.repeat_band);
        let (mut n, mut inside, mut truth_inside, mut in_repeat) = (0usize, 0usize, 0usize, 0usize);
        let mut stds = Vec::with_capacity(sel.len());
        for p in &sel.points {
            let y = ch.eval(&result.params, &p.input);
            let sd = cov.std_at(result, channel, &p.input);
            if !(y.is_finite() && sd.is_finite()) {
                continue;
            }
            n += 1;
            stds.push(sd);
            let band = 1.96 * (sd * sd + cov.residual_rmse * cov.residual_rmse).sqrt();
            if (p.measured - y).abs() <= band {
                inside += 1;
            }
            in_repeat += usize::from((p.measured - y).abs() <= repeat_band);
            if let Some(t) = truth
                && (ch.eval_reference(t, &p.input) - y).abs() <= 1.96 * sd
            {
                truth_inside += 1;
            }
        }
        if n == 0 {
            continue;
        }
        let pct = |k: usize| 100.0 * k as f64 / n as f64;
        out.push(Coverage {
            channel: channel.tydex_name().into(),
            points: n,
            measured_in_band_pct: pct(inside),
            repeat_band,
            measured_in_repeat_band_pct: pct(in_repeat),
            truth_in_band_pct: truth.map(|_| pct(truth_inside)),
            median_std: crate::starts::median(stds).unwrap_or(f64::NAN),
            residual_rmse: cov.residual_rmse,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_grid_has_the_documented_size_and_order() {
        let g = EnvelopeGrid::standard(4000.0, 2.0e5, 16.0);
        assert_eq!(g.len(), 4 * 11 * 5 * 3);
        let x = g.inputs(MapChannel::FxPure, 0.3);
        assert_eq!(x.len(), g.len());
        // pressure fastest, then camber, slip, load
        assert_eq!(x[0].p_pa, 0.85 * 2.0e5);
        assert_eq!(x[1].p_pa, 2.0e5);
        assert_eq!(x[3].gamma_rad, (-2.0f64).to_radians());
        assert_eq!(x[15].kappa, -0.1);
        assert_eq!(x[165].fz_n, 4000.0);
        let y = g.inputs(MapChannel::FyPure, 0.3);
        assert_eq!(y[0].alpha_rad, (-12.0f64).to_radians());
        assert_eq!(y[0].kappa, 0.0);
    }
}
