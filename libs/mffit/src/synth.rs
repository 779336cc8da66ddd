//! Synthetic GS2MF-like data from a known tyre: the stages' unit tests, and a stand-in for rig
//! logs. Sweeps follow the procedures' shapes (variable-rate slip sweeps with asymmetric load
//! and camber coupling, on-centre clumps, rolling-radius holds, step-steer, static longitudinal)
//! at three pressures; forces come from the MF model with Gaussian sensor noise.

use mftyre::{MfInput, TyreParams, UseMode};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::data::{DataKind, Dataset, Procedure, Sample, Segment};

/// Sensor noise (1σ) per channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Forces, N.
    pub force_n: f64,
    /// Vertical load, N.
    pub fz_n: f64,
    /// Moments, N·m.
    pub moment_nm: f64,
    /// Slip angle and camber, deg.
    pub angle_deg: f64,
    /// Slip ratio.
    pub slip_ratio: f64,
    /// Loaded radius, m (before 0.1 mm quantisation).
    pub radius_m: f64,
    /// Noise gains when the drive is coupled (BrkDrv): FX, MZ/MY, MX.
    pub coupled_gain: [f64; 3],
}

impl Noise {
    /// No noise.
    pub const OFF: Noise = Noise {
        force_n: 0.0,
        fz_n: 0.0,
        moment_nm: 0.0,
        angle_deg: 0.0,
        slip_ratio: 0.0,
        radius_m: 0.0,
        coupled_gain: [1.0; 3],
    };
    /// Noise like the virtual rig's defaults (`rigsim` `NoiseParams`), coupled-drive gains
    /// included (coupled MX is 25× noisier: why the thesis fits MX on free-rolling data).
    pub const RIG: Noise = Noise {
        force_n: 35.0,
        fz_n: 25.0,
        moment_nm: 3.0,
        angle_deg: 0.01,
        slip_ratio: 0.0005,
        radius_m: 3e-5,
        coupled_gain: [4.0, 3.0, 25.0],
    };
}

/// What to generate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SynthOptions {
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Noise.
    pub noise: Noise,
    /// Noise seed.
    pub seed: u64,
    /// Pressures (low, mid, high), Pa.
    pub pressures_pa: [f64; 3],
}

impl Default for SynthOptions {
    fn default() -> Self {
        Self { rate_hz: 50.0, noise: Noise::RIG, seed: 1, pressures_pa: [2.1e5, 2.6e5, 3.3e5] }
    }
}

struct Gen<'a> {
    tyre: &'a TyreParams,
    o: SynthOptions,
    rng: ChaCha8Rng,
    fz0: f64,
    v0: f64,
}

impl Gen<'_> {
    fn n(&mut self, sd: f64) -> f64 {
        if sd <= 0.0 {
            return 0.0;
        }
        Normal::new(0.0, sd).map(|d| d.sample(&mut self.rng)).unwrap_or(0.0)
    }

    /// One sample at a true operating point, measured with noise.
    #[allow(clippy::too_many_arguments)] // one argument per channel of the operating point
    fn sample(
        &mut self,
        t: f64,
        fz: f64,
        kappa: f64,
        alpha_deg: f64,
        gamma_deg: f64,
        p: f64,
        v: f64,
        dist: f64,
    ) -> Sample {
        let r0 = self.tyre.unloaded_radius_m();
        let mut input = MfInput {
            fz_n: fz,
            kappa,
            alpha_rad: alpha_deg.to_radians(),
            gamma_rad: gamma_deg.to_radians(),
            phit_per_m: 0.0,
            vx_mps: v,
            p_pa: p,
            omega_radps: v * (1.0 + kappa) / (0.98 * r0),
        };
        // Wheel speed from the effective radius (one fixed-point step is plenty).
        let o = mftyre::evaluate(self.tyre, UseMode::M111, &input);
        input.omega_radps = v * (1.0 + kappa) / o.re_m;
        let o = mftyre::evaluate(self.tyre, UseMode::M111, &input);
        let nz = self.o.noise;
        let [gx, gm, gmx] = if kappa != 0.0 { nz.coupled_gain } else { [1.0; 3] };
        let rl = ((o.rl_m + self.n(nz.radius_m)) / 1e-4).round() * 1e-4;
        Sample {
            time_s: t,
            fz_n: fz + self.n(nz.fz_n),
            kappa: kappa + self.n(nz.slip_ratio),
            alpha_rad: (alpha_deg + self.n(nz.angle_deg)).to_radians(),
            gamma_rad: (gamma_deg + self.n(nz.angle_deg)).to_radians(),
            p_pa: p,
            vx_mps: v,
            omega_radps: input.omega_radps,
            fx_n: o.fx_n + self.n(nz.force_n * gx),
            fy_n: o.fy_n + self.n(nz.force_n),
            mx_nm: o.mx_nm + self.n(nz.moment_nm * gmx),
            my_nm: o.my_nm + self.n(nz.moment_nm * gm),
            mz_nm: o.mz_nm + self.n(nz.moment_nm * gm),
            rl_m: rl,
            temp_c: 45.0,
            temp_inner_c: 45.0,
            temp_outer_c: 45.0,
            road_temp_c: f64::NAN,
            dist_m: dist,
        }
    }

    /// A variable-rate sweep 0 → +peak → −peak → 0 of `slip` (low rate below the threshold).
    fn path(&self, peak: f64, low: f64, high: f64, threshold: f64) -> Vec<f64> {
        let dt = 1.0 / self.o.rate_hz;
        let mut out = vec![0.0];
        let mut x: f64 = 0.0;
        for target in [peak, -peak, 0.0] {
            loop {
                let rate = if x.abs() < threshold { low } else { high };
                let step = rate * dt;
                if (target - x).abs() <= step {
                    x = target;
                    out.push(x);
                    break;
                }
                x += step * (target - x).signum();
                out.push(x);
            }
        }
        out
    }
}

/// Lateral weight transfer: load factor at −SA `hi`, at +SA `lo`, saturating at |SA| = 5°.
fn asym(alpha_deg: f64, hi: f64, lo: f64) -> f64 {
    let s = (-alpha_deg / 5.0).clamp(-1.0, 1.0);
    0.5 * (hi + lo) + 0.5 * (hi - lo) * s
}

fn segment(procedure: Procedure, kind: DataKind, section: &str, sweep: String, samples: Vec<Sample>) -> Segment {
    Segment { procedure, kind, section: section.into(), sweep, samples, cell: None, origin: None }
}

/// Generates a full GS2MF-like dataset (FreeRolling, BrkDrv, StaticLong) from `tyre`.
pub fn gs2mf(tyre: &TyreParams, o: SynthOptions) -> Dataset {
    let mut g = Gen { tyre, o, rng: ChaCha8Rng::seed_from_u64(o.seed), fz0: tyre.fnomin_n(), v0: tyre.longvl_mps() };
    let dt = 1.0 / o.rate_hz;
    let fz0 = g.fz0;
    let v0 = g.v0;
    let mut segs = Vec::new();
    let fr = Procedure::FreeRolling;
    let bd = Procedure::BrkDrv;

    // Step-steer at the mid pressure: FY builds up over the relaxation length.
    for &lf in &[0.5, 0.75, 1.0, 1.5] {
        for &a in &[1.5_f64, -1.5] {
            let p = o.pressures_pa[1];
            let probe = MfInput {
                fz_n: lf * fz0,
                kappa: 0.0,
                alpha_rad: 0.0,
                gamma_rad: 0.0,
                phit_per_m: 0.0,
                vx_mps: v0,
                p_pa: p,
                omega_radps: 0.0,
            };
            let sigma = mftyre::evaluate(tyre, UseMode::M111, &probe).sigmay_m;
            let ss =
                mftyre::pure_fy(tyre, UseMode::M111, &MfInput { alpha_rad: a.to_radians(), fz_n: lf * fz0, ..probe });
            let mut s = Vec::new();
            // Standstill with the wheel steered, then roll at 1 m/s for 1.5 m.
            for i in 0..10 {
                let mut smp = g.sample(i as f64 * dt, lf * fz0, 0.0, a, 0.0, p, 0.0, 0.0);
                smp.fy_n = g.n(o.noise.force_n);
                s.push(smp);
            }
            let n = (1.5 / 1.0 * o.rate_hz) as usize;
            for i in 0..n {
                let d = i as f64 * dt * 1.0;
                let mut smp = g.sample((i + 10) as f64 * dt, lf * fz0, 0.0, a, 0.0, p, 1.0, d);
                smp.fy_n = ss * (1.0 - (-d / sigma).exp()) + g.n(o.noise.force_n);
                s.push(smp);
            }
            segs.push(segment(fr, DataKind::StepSteer, "step_steer", format!("StepSteer_Fz{lf}_SA{a}"), s));
        }
    }
    for (pi, &p) in o.pressures_pa.iter().enumerate() {
        // On-centre clumps and rolling-radius holds.
        let mut s = Vec::new();
        let mut t = 0.0;
        for &a in &[1.0, 0.0, -1.0] {
            for &lf in &[0.7, 1.0, 1.35, 1.7, 2.0] {
                for _ in 0..(3.0 * o.rate_hz) as usize {
                    s.push(g.sample(t, lf * fz0, 0.0, a, 0.0, p, v0, t * v0));
                    t += dt;
                }
            }
        }
        segs.push(segment(fr, DataKind::OnCentre, "on_centre_rolling_radius", format!("OnCentre_p{pi}"), s));
        let mut s = Vec::new();
        let mut t = 0.0;
        for &v in &[5.5, 16.6, 38.8] {
            for &lf in &[0.4, 0.65, 0.9, 1.2, 1.5, 1.75, 2.0] {
                for _ in 0..(2.0 * o.rate_hz) as usize {
                    s.push(g.sample(t, lf * fz0, 0.0, 0.0, 0.0, p, v, t * v));
                    t += dt;
                }
            }
        }
        segs.push(segment(fr, DataKind::RollingRadius, "on_centre_rolling_radius", format!("RollingRadius_p{pi}"), s));

        // Force & moment sweeps: (peak deg, load hi, load lo, camber law).
        type Law = fn(f64) -> f64;
        let sweeps: [(f64, f64, f64, Law, &str); 9] = [
            (16.0, 1.6, 0.4, |_| 0.0, "zero_camber"),
            (16.0, 1.6, 0.4, |a| 1.8 * (a / 5.0).clamp(-1.0, 1.0), "camber_with"),
            (16.0, 1.6, 0.4, |a| -1.8 * (a / 5.0).clamp(-1.0, 1.0), "camber_adverse"),
            (4.0, 1.4, 0.6, |_| 3.0, "low_slip_camber3"),
            (4.0, 1.4, 0.6, |_| -3.0, "low_slip_camber-3"),
            (22.0, 1.8, 0.6, |_| 0.8, "camber0.8_high"),
            (22.0, 1.4, 0.2, |_| 0.8, "camber0.8_low"),
            (12.0, 2.0, 2.0, |_| 0.0, "const_high"),
            (12.0, 0.5, 0.5, |_| 0.0, "const_low"),
        ];
        for (si, (peak, hi, lo, law, name)) in sweeps.iter().enumerate() {
            let path = g.path(*peak, 2.0, 30.0, 4.0);
            let s: Vec<Sample> = path
                .iter()
                .enumerate()
                .map(|(i, &a)| {
                    g.sample(i as f64 * dt, asym(a, *hi, *lo) * fz0, 0.0, a, law(a), p, v0, i as f64 * dt * v0)
                })
                .collect();
            segs.push(segment(fr, DataKind::Sweep, "force_moment", format!("FreeRoll_sw{si}_{name}_p{pi}"), s));
        }

        // BrkDrv pure longitudinal: loads × pressures, then camber at two loads (mid pressure).
        let mut long: Vec<(f64, f64, f64, f64, f64)> =
            [0.25, 0.6, 1.0, 1.5, 2.25].iter().map(|&l| (l, 0.0, 0.0, 0.25, 0.0)).collect();
        if pi == 1 {
            for &l in &[0.6, 1.4] {
                for &c in &[-5.0, -3.0, 3.0, 5.0] {
                    long.push((l, 0.0, c, 0.25, 0.0));
                }
            }
            // Combined A/B/D and extreme.
            for &(a, l, c) in &[
                (8.5, 0.6, 0.0),
                (8.5, 0.6, -3.0),
                (-8.5, 1.4, 0.0),
                (-8.5, 1.4, -3.0),
                (5.0, 1.0, 5.0),
                (-5.0, 1.0, -5.0),
            ] {
                long.push((l, a, c, 0.25, 0.0));
            }
            for &l in &[0.6, 1.0, 1.5] {
                long.push((l, 1.0, 0.0, 0.1, 0.0));
                long.push((l, -1.0, 0.0, 0.1, 0.0));
            }
            long.push((1.0, -12.0, 0.0, 0.25, 0.0));
            long.push((1.0, 12.0, 0.0, 0.25, 0.0));
            long.push((0.25, 18.0, 0.0, 0.4, 0.0));
            long.push((2.0, -18.0, 0.0, 0.4, 0.0));
        }
        // Inflation pressure A: SA ±3°, three loads, every pressure.
        for &l in &[0.6, 1.0, 1.5] {
            long.push((l, 3.0, 0.0, 0.1, 0.0));
            long.push((l, -3.0, 0.0, 0.1, 0.0));
        }
        for (li, &(l, a, c, peak, _)) in long.iter().enumerate() {
            let path = g.path(peak, 0.10, 0.60, 0.02);
            let s: Vec<Sample> = path
                .iter()
                .enumerate()
                .map(|(i, &k)| g.sample(i as f64 * dt, l * fz0, k, a, c, p, v0, i as f64 * dt * v0))
                .collect();
            let kind = "pure_long";
            segs.push(segment(
                bd,
                DataKind::Sweep,
                if a == 0.0 { kind } else { "combined" },
                format!("BrkDrv_sw{li}_p{pi}"),
                s,
            ));
        }

        // Static longitudinal: six loads, belt moved 0.1 m.
        for &l in &[0.4, 0.6, 0.8, 1.0, 1.2, 1.4] {
            let probe = MfInput {
                fz_n: l * fz0,
                kappa: 0.0,
                alpha_rad: 0.0,
                gamma_rad: 0.0,
                phit_per_m: 0.0,
                vx_mps: v0,
                p_pa: p,
                omega_radps: 0.0,
            };
            let o_m = mftyre::evaluate(tyre, UseMode::M111, &probe);
            let limit = tyre.get("PDX1").unwrap_or(1.0) * l * fz0;
            let s: Vec<Sample> = (0..100)
                .map(|i| {
                    let d = i as f64 * 0.001;
                    let fx = -(o_m.cx_npm * d).min(limit);
                    let mut smp = g.sample(i as f64 * 0.1, l * fz0, 0.0, 0.0, 0.0, p, 0.0, d);
                    smp.fx_n = fx + g.n(o.noise.force_n);
                    smp.fy_n = g.n(o.noise.force_n);
                    smp.vx_mps = 0.01;
                    smp
                })
                .collect();
            segs.push(segment(
                Procedure::StaticLong,
                DataKind::StaticLong,
                "static_long",
                format!("Static_Fz{l}_p{pi}"),
                s,
            ));
        }
    }
    Dataset { segments: segs, fnomin_n: Some(fz0), sources: vec!["synthetic".into()] }
}

/// The shape of a Calspan TTC run (see `docs/real-data.md`): which cells, in which order.
#[derive(Debug, Clone, PartialEq)]
pub struct TtcShape {
    /// Cornering run: pressures, Pa; loads per pressure, N (in run order); cambers, deg.
    pub cornering_pressures_pa: Vec<f64>,
    /// Loads of the cornering sweeps, N.
    pub cornering_loads_n: Vec<f64>,
    /// Cambers of the cornering run, deg.
    pub cornering_cambers_deg: Vec<f64>,
    /// Peak slip angle of a cornering sweep, deg.
    pub cornering_peak_deg: f64,
    /// Drive/brake/combined run: one pressure, Pa.
    pub drive_pressure_pa: f64,
    /// Loads, N.
    pub drive_loads_n: Vec<f64>,
    /// Cambers, deg.
    pub drive_cambers_deg: Vec<f64>,
    /// Held slip angles, deg.
    pub drive_slip_angles_deg: Vec<f64>,
    /// Peak slip ratio of a drive/brake sweep.
    pub drive_peak_kappa: f64,
    /// Road speed, m/s.
    pub speed_mps: f64,
}

impl TtcShape {
    /// A race tyre's runs as the shared notes describe them (FSAE scale).
    pub fn race() -> Self {
        TtcShape {
            cornering_pressures_pa: vec![70e3, 84e3, 98e3, 112e3],
            cornering_loads_n: vec![1100.0, 1540.0, 660.0, 220.0, 1100.0, 440.0],
            cornering_cambers_deg: vec![0.0],
            cornering_peak_deg: 13.0,
            drive_pressure_pa: 83e3,
            drive_loads_n: vec![220.0, 660.0, 1100.0, 1540.0],
            drive_cambers_deg: vec![0.0, 2.0, 4.0],
            drive_slip_angles_deg: vec![0.0, 3.0, 6.0],
            drive_peak_kappa: 0.2,
            speed_mps: 40.0 / 3.6,
        }
    }
}

/// Noise of a small (FSAE) tyre's rig channels.
pub const RACE_NOISE: Noise = Noise {
    force_n: 6.0,
    fz_n: 4.0,
    moment_nm: 0.4,
    angle_deg: 0.02,
    slip_ratio: 0.0005,
    radius_m: 3e-5,
    coupled_gain: [2.0, 2.0, 5.0],
};

/// Synthetic TTC-shaped runs from `tyre`: `(cornering, drive_brake_combined)`, each segment a
/// sweep with its [`Cell`](crate::data::Cell), conditioning sweeps as [`DataKind::WarmUp`]. The
/// forces come from the MF model itself: these data test the fitter's structure (which
/// coefficients a TTC run identifies), not its fidelity to real tyres.
pub fn ttc_runs(tyre: &TyreParams, shape: &TtcShape, o: SynthOptions) -> (Dataset, Dataset) {
    use crate::data::{Cell, SweepKind};
    let mut g = Gen { tyre, o, rng: ChaCha8Rng::seed_from_u64(o.seed), fz0: tyre.fnomin_n(), v0: shape.speed_mps };
    let dt = 1.0 / o.rate_hz;
    let v = shape.speed_mps;
    let median = |s: &[Sample], f: fn(&Sample) -> f64| {
        let mut x: Vec<f64> = s.iter().map(f).collect();
        x.sort_by(f64::total_cmp);
        x[x.len() / 2]
    };
    let cell = |s: &[Sample], kind: SweepKind, reach: f64| Cell {
        kind,
        fz_n: median(s, |x| x.fz_n),
        p_pa: median(s, |x| x.p_pa),
        gamma_rad: median(s, |x| x.gamma_rad),
        alpha_rad: if kind == SweepKind::Cornering { 0.0 } else { median(s, |x| x.alpha_rad) },
        kappa: 0.0,
        vx_mps: v,
        slip_reach: reach,
    };
    let mut cornering = Vec::new();
    let mut t = 0.0;
    for &p in &shape.cornering_pressures_pa {
        for &gam in &shape.cornering_cambers_deg {
            // A conditioning sweep to a few degrees, then the sweeps.
            let path = g.path(4.0, 2.0, 2.0, 1.0);
            let s: Vec<Sample> = path
                .iter()
                .map(|&a| {
                    t += dt;
                    g.sample(t, 0.5 * g.fz0, 0.0, a, gam, p, v, t * v)
                })
                .collect();
            cornering.push(segment(
                Procedure::FreeRolling,
                DataKind::WarmUp,
                "ttc_cornering",
                format!("conditioning P{:.0}", p / 1e3),
                s,
            ));
            for &fz in &shape.cornering_loads_n {
                let path = g.path(shape.cornering_peak_deg, 2.1, 2.1, 1.0);
                let s: Vec<Sample> = path
                    .iter()
                    .map(|&a| {
                        t += dt;
                        g.sample(t, fz, 0.0, a, gam, p, v, t * v)
                    })
                    .collect();
                let c = cell(&s, SweepKind::Cornering, shape.cornering_peak_deg.to_radians());
                let mut seg = segment(
                    Procedure::FreeRolling,
                    DataKind::Sweep,
                    "ttc_cornering",
                    format!("cornering P{:.0}kPa FZ{fz:.0}N IA{gam:.0}", p / 1e3),
                    s,
                );
                seg.cell = Some(c);
                cornering.push(seg);
            }
        }
    }
    let mut drive = Vec::new();
    let p = shape.drive_pressure_pa;
    for &gam in &shape.drive_cambers_deg {
        for &a in &shape.drive_slip_angles_deg {
            for &fz in &shape.drive_loads_n {
                let path = g.path(shape.drive_peak_kappa, 0.12, 0.12, 0.02);
                let s: Vec<Sample> = path
                    .iter()
                    .map(|&k| {
                        t += dt;
                        g.sample(t, fz, k, a, gam, p, v, t * v)
                    })
                    .collect();
                let kind = if a.abs() < 0.5 { SweepKind::DriveBrake } else { SweepKind::Combined };
                let c = cell(&s, kind, shape.drive_peak_kappa);
                let mut seg = segment(
                    Procedure::BrkDrv,
                    DataKind::Sweep,
                    "ttc_drive_brake",
                    format!("{} SA{a:.0} FZ{fz:.0}N IA{gam:.0}", kind.name()),
                    s,
                );
                seg.cell = Some(c);
                drive.push(seg);
            }
        }
    }
    let ds = |segments| Dataset { segments, fnomin_n: None, sources: vec!["synthetic TTC run".into()] };
    (ds(cornering), ds(drive))
}
