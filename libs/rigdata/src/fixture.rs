//! Synthetic TTC-like runs for tests and benchmarks: what a Calspan run file looks like around
//! its sweeps — standstill at both ends (where `SR` reads about −0.9), load and pressure ramps
//! between cells, the wheel lifted at the end, conditioning sweeps to a few degrees, repeated sweeps, `SR` ≠ `SL` (offset and
//! noisy while `SL` is exactly 0 in cornering), SAE signs, 50 Hz, an ambient temperature in °F
//! labelled °C — with the list of sweeps it holds, so a test can check that a reader finds them.
//!
//! The forces are a simple Magic-Formula-like curve with friction ellipse; they only need signs
//! and magnitudes like a race tyre's (the physical virtual tyre lives in `rigsim`).

use mffit::SweepKind;

use crate::mat::MatUnits;
use crate::table::ChannelTable;

/// A sweep the fixture holds.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedSweep {
    /// Kind.
    pub kind: SweepKind,
    /// A conditioning sweep.
    pub conditioning: bool,
    /// Load, N.
    pub fz_n: f64,
    /// Pressure, kPa.
    pub p_kpa: f64,
    /// Camber, deg.
    pub ia_deg: f64,
    /// Held slip angle (ISO-W), deg.
    pub sa_deg: f64,
    /// A camber sweep (camber stepped at the held slip angle `sa_deg`; `ia_deg` its median).
    pub camber_sweep: bool,
}

/// A synthetic run and its sweeps.
#[derive(Debug, Clone)]
pub struct FixtureRun {
    /// The file's channels (TTC names and units, SAE signs).
    pub table: ChannelTable,
    /// The sweeps in order.
    pub sweeps: Vec<PlannedSweep>,
}

/// What kind of run to make.
#[derive(Debug, Clone, PartialEq)]
pub struct FixtureSpec {
    /// Cornering (slip-angle sweeps) or drive/brake/combined (slip-ratio sweeps).
    pub cornering: bool,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Pressures, kPa.
    pub pressures_kpa: Vec<f64>,
    /// Loads, N; the first is also where the conditioning sweep runs and is repeated at the end
    /// of each pressure, as TTC runs do.
    pub loads_n: Vec<f64>,
    /// Cambers, deg.
    pub cambers_deg: Vec<f64>,
    /// Held slip angles for slip-ratio sweeps (ISO-W), deg.
    pub slip_angles_deg: Vec<f64>,
    /// Sweep duration, s.
    pub sweep_s: f64,
    /// Include `SL` (else only `SR`, as some files).
    pub with_sl: bool,
    /// Noise seed.
    pub seed: u64,
    /// How the units line is spelled (and the values scaled).
    pub units: UnitStyle,
    /// An older round's file: a title with no tyre name, no `testid`, no `NFX`.
    pub older_round: bool,
    /// The load wanders while the slip angle sweeps, by up to this fraction of its setpoint
    /// (−0.65× at one end of the sweep, +1× at the other, as some rounds' load control does).
    pub fz_wander: f64,
    /// A camber sweep at the end of each pressure: camber stepped through these levels at the
    /// held slip angle (`sa_deg`, ISO-W), first load.
    pub camber_sweep: Option<CamberSweep>,
    /// Full-reach warm-up sweeps opening a drive/brake run at the last load (a cell the run
    /// sweeps again later) instead of the short conditioning sweeps; 0 for none.
    pub warmup_sweeps: usize,
    /// The load (or slip angle) for the next cell set right as a sweep comes back to zero, with
    /// no rolling at the cell after it (as real runs often do).
    pub no_settle_after_sweeps: bool,
    /// Slip-ratio reach of the drive/brake sweeps (0.2 in TTC runs, 0.65 in pure longitudinal
    /// runs of some rounds).
    pub kappa_reach: f64,
    /// The tyre starts this much colder than its running tread temperature, K, and closes the
    /// gap as it is swept (by e⁻¹ every 1.2 sweep durations of sweeping): a run begun on a cold
    /// tyre; 0 for a tyre brought to temperature before the file begins.
    pub cold_start_k: f64,
    /// The tread heated by sliding, as real runs' lasers read it; `None`: the lasers read a
    /// plain ramp through the run (and `cold_start_k`).
    pub tread_heating: Option<TreadHeating>,
}

/// A tread surface heated by the power it slides with: dT/dt = gain·P − (T − T_base)/τ, P the
/// sliding power |FY·V·sin α| + |FX·κ·V|, T_base climbing linearly through the run (the
/// carcass and the room warming). Real runs' tread temperatures rise in each sweep, most at high
/// load and slip, and fall back between sweeps (`../shared/real-rig-data.md`); a plain ramp in
/// time ties the temperature to the order the cells are run in, which no rig's does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreadHeating {
    /// T_base at the start and at the end of the run, °C.
    pub base_c: [f64; 2],
    /// Heating per unit of sliding power, K/s per kW.
    pub k_per_kj: f64,
    /// Time constant of the surface's cooling towards T_base, s.
    pub cooling_s: f64,
}

/// A camber sweep: camber stepped at a held slip angle.
#[derive(Debug, Clone, PartialEq)]
pub struct CamberSweep {
    /// Held slip angle (ISO-W), deg.
    pub sa_deg: f64,
    /// Camber levels in order, deg.
    pub cambers_deg: Vec<f64>,
}

/// Units lines of different test rounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum UnitStyle {
    /// `s kph rpm deg cm kPa N N-m none degC`.
    #[default]
    Ttc,
    /// A later round's spellings: `sec`, `Nm`, `deg C`, `deg F` (AMBTMP, then honestly °F), `SAE`
    /// for SL.
    LaterRound,
    /// US units where the file says so: mph, in, psi, lbf, degF.
    Imperial,
    /// TTC's "USCS" distribution of a run: lb, psi, in, mph, ft-lb, deg F.
    Uscs,
}

impl FixtureSpec {
    /// A small cornering run: two pressures, three loads plus a repeat, camber 0.
    pub fn cornering() -> Self {
        Self {
            cornering: true,
            rate_hz: 50.0,
            pressures_kpa: vec![83.0, 97.0],
            loads_n: vec![1100.0, 660.0, 1540.0],
            cambers_deg: vec![0.0],
            slip_angles_deg: vec![0.0],
            sweep_s: 12.0,
            with_sl: true,
            seed: 1,
            units: UnitStyle::Ttc,
            older_round: false,
            fz_wander: 0.0,
            camber_sweep: None,
            warmup_sweeps: 0,
            no_settle_after_sweeps: false,
            kappa_reach: 0.2,
            cold_start_k: 0.0,
            tread_heating: None,
        }
    }

    /// A small drive/brake/combined run: one pressure, two loads, cambers 0 and 2°, slip
    /// angles 0 and 3°.
    pub fn drive_brake() -> Self {
        Self {
            cornering: false,
            rate_hz: 50.0,
            pressures_kpa: vec![83.0],
            loads_n: vec![1100.0, 660.0],
            cambers_deg: vec![0.0, 2.0],
            slip_angles_deg: vec![0.0, 3.0],
            sweep_s: 5.0,
            with_sl: true,
            seed: 2,
            units: UnitStyle::Ttc,
            older_round: false,
            fz_wander: 0.0,
            camber_sweep: None,
            warmup_sweeps: 0,
            no_settle_after_sweeps: false,
            kappa_reach: 0.2,
            cold_start_k: 0.0,
            tread_heating: None,
        }
    }

    /// A race tyre's cornering run laid out as real TTC cornering runs are
    /// (`../shared/real-rig-data.md`): four pressures (70 / 84 / 98 / 112 kPa), at each two
    /// conditioning sweeps at 1,100 N, then ±12° sweeps of 25 s at 1,100 / 1,540 / 660 / 220 /
    /// 440 N and 1,100 N again; the load wandering up to 15 % through each sweep, as some rounds'
    /// load control does; the tread heated by sliding on a base warming from 40 to 45 °C.
    pub fn race_cornering_heated() -> Self {
        Self {
            pressures_kpa: vec![70.0, 84.0, 98.0, 112.0],
            loads_n: vec![1100.0, 1540.0, 660.0, 220.0, 440.0],
            sweep_s: 25.0,
            fz_wander: 0.15,
            seed: 2,
            tread_heating: Some(TreadHeating { base_c: [40.0, 45.0], k_per_kj: 0.5, cooling_s: 20.0 }),
            ..Self::cornering()
        }
    }

    /// The drive/brake/combined run of the same tyre, laid out as real ones are: one pressure
    /// (84 kPa), five full warm-up sweeps at 1,100 N, then slip-ratio sweeps to ±0.2 of 6 s at
    /// cambers 0 / 2 / 4°, slip angles 0 / 3 / 6° and loads 220 / 660 / 1,540 / 1,100 N, and
    /// 220 N again at the end; the tread heated by sliding on a base warming from 50 to 70 °C.
    pub fn race_drive_brake_heated() -> Self {
        Self {
            pressures_kpa: vec![84.0],
            loads_n: vec![220.0, 660.0, 1540.0, 1100.0],
            cambers_deg: vec![0.0, 2.0, 4.0],
            slip_angles_deg: vec![0.0, 3.0, 6.0],
            sweep_s: 6.0,
            warmup_sweeps: 5,
            seed: 102,
            tread_heating: Some(TreadHeating { base_c: [50.0, 70.0], k_per_kj: 0.5, cooling_s: 20.0 }),
            ..Self::drive_brake()
        }
    }
}

/// Deterministic noise (xorshift64* with Box–Muller), so fixtures need no random crate.
struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    fn normal(&mut self, sd: f64) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        sd * (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }
}

#[derive(Debug, Clone, Copy)]
struct State {
    v_kph: f64,
    fz_n: f64,
    p_kpa: f64,
    ia_deg: f64,
    sa_deg: f64,
    sl: f64,
    /// Time spent sweeping so far, s (what warms a cold tyre).
    swept_s: f64,
}

struct Builder {
    /// Load wander over a slip-angle sweep (fraction of the setpoint).
    wander: f64,
    dt: f64,
    t: f64,
    s: State,
    rows: Vec<(f64, State)>,
}

impl Builder {
    fn steps(&self, dur: f64) -> usize {
        (dur / self.dt).round().max(1.0) as usize
    }

    fn hold(&mut self, dur: f64) {
        for _ in 0..self.steps(dur) {
            self.t += self.dt;
            self.rows.push((self.t, self.s));
        }
    }

    fn ramp(&mut self, dur: f64, to: State) {
        let from = self.s;
        let n = self.steps(dur);
        for k in 1..=n {
            let f = k as f64 / n as f64;
            let l = |a: f64, b: f64| a + (b - a) * f;
            self.s = State {
                v_kph: l(from.v_kph, to.v_kph),
                fz_n: l(from.fz_n, to.fz_n),
                p_kpa: l(from.p_kpa, to.p_kpa),
                ia_deg: l(from.ia_deg, to.ia_deg),
                sa_deg: l(from.sa_deg, to.sa_deg),
                sl: l(from.sl, to.sl),
                swept_s: from.swept_s,
            };
            self.t += self.dt;
            self.rows.push((self.t, self.s));
        }
    }

    /// 0 → −amp → +amp → 0 (triangle) on the slip angle or the slip ratio.
    fn sweep(&mut self, dur: f64, amp: f64, on_sa: bool) {
        let n = self.steps(dur);
        let base = self.s;
        for k in 1..=n {
            let f = k as f64 / n as f64;
            let x = if f < 0.25 {
                -4.0 * f
            } else if f < 0.75 {
                -1.0 + 4.0 * (f - 0.25)
            } else {
                1.0 - 4.0 * (f - 0.75)
            };
            let mut s = State { swept_s: base.swept_s + dur * f, ..base };
            if on_sa {
                s.sa_deg = amp * x;
                s.fz_n = base.fz_n * (1.0 + self.wander * x * x * if x > 0.0 { 1.0 } else { -0.65 });
            } else {
                s.sl = amp * x;
            }
            self.s = s;
            self.t += self.dt;
            self.rows.push((self.t, s));
        }
        self.s = State { swept_s: base.swept_s + dur, ..base };
    }
}

/// Makes a synthetic run.
pub fn ttc_run(spec: &FixtureSpec) -> FixtureRun {
    let mut b = Builder {
        wander: spec.fz_wander,
        dt: 1.0 / spec.rate_hz,
        t: -1.0 / spec.rate_hz,
        s: State {
            v_kph: 0.0,
            fz_n: 0.0,
            p_kpa: spec.pressures_kpa[0],
            ia_deg: 0.0,
            sa_deg: 0.0,
            sl: 0.0,
            swept_s: 0.0,
        },
        rows: Vec::new(),
    };
    let mut sweeps = Vec::new();
    // Standstill: loaded at zero speed, then up to speed.
    b.hold(1.0);
    b.ramp(1.0, State { fz_n: 220.0, ..b.s });
    b.hold(3.0);
    b.ramp(3.0, State { v_kph: 40.0, ..b.s });
    let plan = |b: &mut Builder, sweeps: &mut Vec<PlannedSweep>, to: State, conditioning: bool, amp: f64| {
        b.ramp(2.0, to);
        b.hold(1.5);
        b.sweep(if conditioning { spec.sweep_s * 0.5 } else { spec.sweep_s }, amp, spec.cornering);
        if !spec.no_settle_after_sweeps {
            b.hold(1.0);
        }
        let kind = if spec.cornering {
            SweepKind::Cornering
        } else if to.sa_deg.abs() < 1.0 {
            SweepKind::DriveBrake
        } else {
            SweepKind::Combined
        };
        // ISO-W slip angle held: the file's SAE angle flips.
        sweeps.push(PlannedSweep {
            kind,
            conditioning,
            fz_n: to.fz_n,
            p_kpa: to.p_kpa,
            ia_deg: to.ia_deg,
            sa_deg: -to.sa_deg,
            camber_sweep: false,
        });
    };
    let mut opens_cold = spec.cold_start_k > 0.0;
    for &p in &spec.pressures_kpa {
        // Pressure set at light load.
        b.ramp(2.0, State { fz_n: 220.0, sa_deg: 0.0, sl: 0.0, ..b.s });
        b.ramp(4.0, State { p_kpa: p, ..b.s });
        b.hold(1.0);
        let first = State { fz_n: spec.loads_n[0], ia_deg: spec.cambers_deg[0], sa_deg: 0.0, ..b.s };
        let cond_amp = if spec.cornering { 3.0 } else { 0.04 };
        let amp = if spec.cornering { 12.0 } else { spec.kappa_reach };
        if spec.warmup_sweeps > 0 {
            // Warm-up: full sweeps at the last load, a cell swept again below.
            let warm = State { fz_n: spec.loads_n[spec.loads_n.len() - 1], ..first };
            for _ in 0..spec.warmup_sweeps {
                plan(&mut b, &mut sweeps, warm, true, amp);
            }
        } else {
            // The conditioning sweeps: two short ones back to back.
            plan(&mut b, &mut sweeps, first, true, cond_amp);
            b.sweep(spec.sweep_s * 0.5, cond_amp, spec.cornering);
            b.hold(1.0);
        }
        for &ia in &spec.cambers_deg {
            for &sa in &spec.slip_angles_deg {
                for &fz in &spec.loads_n {
                    let to = State { fz_n: fz, ia_deg: ia, sa_deg: -sa, ..b.s };
                    plan(&mut b, &mut sweeps, to, false, amp);
                    if let Some(s) = sweeps.last_mut().filter(|_| opens_cold) {
                        // The run's first full sweep, on a tread still well below its running
                        // temperature; its cell is swept again at the end of the pressure.
                        s.conditioning = true;
                        opens_cold = false;
                    }
                }
            }
        }
        // A repeat at the first load, as TTC runs end each pressure.
        let to = State { fz_n: spec.loads_n[0], ia_deg: spec.cambers_deg[0], sa_deg: 0.0, ..b.s };
        plan(&mut b, &mut sweeps, to, false, amp);
        if let Some(cs) = &spec.camber_sweep {
            camber_sweep(&mut b, &mut sweeps, cs, spec.loads_n[0]);
        }
    }
    // Unloaded at speed (wheel lifted), then the belt stops.
    b.ramp(2.0, State { fz_n: 0.0, sa_deg: 0.0, sl: 0.0, ia_deg: 0.0, ..b.s });
    b.hold(2.0);
    b.ramp(3.0, State { v_kph: 0.0, ..b.s });
    b.hold(2.0);
    FixtureRun { table: tabulate(spec, &b.rows), sweeps }
}

/// Camber stepped through `cs.cambers_deg` at the held slip angle, then back to camber 0 and
/// slip angle 0.
fn camber_sweep(b: &mut Builder, sweeps: &mut Vec<PlannedSweep>, cs: &CamberSweep, fz_n: f64) {
    let first = cs.cambers_deg.first().copied().unwrap_or(0.0);
    // SAE in the file: the ISO-W slip angle flips.
    b.ramp(2.0, State { fz_n, ia_deg: first, sa_deg: 0.0, ..b.s });
    b.hold(1.0);
    b.ramp(1.0, State { sa_deg: -cs.sa_deg, ..b.s });
    b.hold(3.0);
    for &ia in cs.cambers_deg.iter().skip(1) {
        b.ramp(0.5, State { ia_deg: ia, ..b.s });
        b.hold(3.0);
    }
    let mut levels = cs.cambers_deg.clone();
    levels.sort_by(f64::total_cmp);
    sweeps.push(PlannedSweep {
        kind: SweepKind::Cornering,
        conditioning: false,
        fz_n,
        p_kpa: b.s.p_kpa,
        ia_deg: levels.get(levels.len() / 2).copied().unwrap_or(0.0),
        sa_deg: cs.sa_deg,
        camber_sweep: true,
    });
    b.ramp(1.0, State { sa_deg: 0.0, ..b.s });
    b.hold(1.0);
    b.ramp(1.0, State { ia_deg: 0.0, ..b.s });
    b.hold(1.0);
}

fn tabulate(spec: &FixtureSpec, rows: &[(f64, State)]) -> ChannelTable {
    let mut nz = Noise(spec.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let n = rows.len();
    let mut c: Vec<Vec<f64>> = (0..23).map(|_| Vec::with_capacity(n)).collect();
    let t_end = rows.last().map(|r| r.0).unwrap_or(1.0).max(1.0);
    let mut surface_c = spec.tread_heating.map_or(f64::NAN, |h| h.base_c[0]);
    let mut last_t = rows.first().map_or(0.0, |r| r.0);
    for (t, s) in rows {
        let fz = s.fz_n + nz.normal(8.0);
        let alpha = (-s.sa_deg).to_radians(); // ISO-W
        let gamma = s.ia_deg.to_radians();
        let kappa = s.sl;
        // Friction falls with load (race tyre, μ ≈ 2.5 at light load).
        let mu = 2.6 - 0.3 * (fz / 1500.0);
        let (bx, by) = (12.0, 9.0);
        let sx = (bx * kappa).atan() * 1.6;
        let sy = (by * alpha).atan() * 1.4;
        let fx0 = mu * fz * sx.sin();
        let fy0 = -mu * fz * sy.sin() + 0.8 * fz * gamma;
        // Combined: each force reduced by the other's share of friction.
        let gx = (1.0 / (1.0 + (4.0 * alpha).powi(2))).sqrt();
        let gy = (1.0 / (1.0 + (6.0 * kappa).powi(2))).sqrt();
        let (fx, fy) = (fx0 * gx, fy0 * gy);
        // Aligning moment as a tyre makes it: the pneumatic trail shrinks with the combined
        // (equivalent) slip, the slip ratio scaled by the stiffness ratio, so driving or braking
        // takes the trail away as sliding spreads through the contact patch; and FX acts on an
        // arm that grows with the lateral deflection (FY/FZ).
        let alpha_eq = (alpha.powi(2) + (bx * 1.6 / (by * 1.4) * kappa).powi(2)).sqrt();
        let mz = -0.02 * fy * (1.0 - (alpha_eq / 0.2).min(1.0)) + 0.004 * fy / fz.abs().max(1.0) * fx;
        let mx = -0.005 * fy + 0.02 * fz * gamma;
        let rl = 0.258 - fz / 150_000.0;
        let re = 0.255 - fz / 300_000.0;
        let v = s.v_kph + if s.v_kph > 0.0 { nz.normal(0.05) } else { 0.0 };
        let omega = v / 3.6 / re * (1.0 + kappa);
        let rolling = s.v_kph > 1.0;
        // The rig's SR grows with slip angle and load while the wheel rolls free (−0.01 at small
        // angles, about −0.07 at 12° and 2 kN), besides its offset and noise.
        let sr_free = -0.01 - 0.07 * (s.sa_deg / 12.0).powi(2) * (fz / 2000.0);
        let sr = if rolling { kappa + sr_free + nz.normal(0.006) } else { -0.9 + nz.normal(0.01) };
        let temp = match spec.tread_heating {
            Some(h) => {
                let dt = (t - last_t).max(0.0);
                let base = h.base_c[0] + (h.base_c[1] - h.base_c[0]) * t / t_end;
                let speed = s.v_kph / 3.6;
                let power_kw = ((fy * speed * alpha.sin()).abs() + (fx * kappa * speed).abs()) / 1000.0;
                surface_c += dt * (h.k_per_kj * power_kw - (surface_c - base) / h.cooling_s.max(dt));
                surface_c
            }
            None => {
                45.0 + 11.0 * t / t_end + if spec.cornering { 0.0 } else { 40.0 * t / t_end - 7.0 }
                    - spec.cold_start_k * (-s.swept_s / (1.2 * spec.sweep_s)).exp()
            }
        };
        last_t = *t;
        // SAE as written: FY, FZ, SA, MZ flip.
        let vals = [
            *t,
            v,
            omega * 30.0 / std::f64::consts::PI,
            s.sa_deg + nz.normal(0.02),
            s.ia_deg + nz.normal(0.01),
            rl * 100.0,
            if rolling { re * 100.0 } else { 100.0 + nz.normal(40.0) },
            s.p_kpa + nz.normal(0.3),
            fx + nz.normal(10.0),
            -fy + nz.normal(10.0),
            -fz,
            mx + nz.normal(0.5),
            -mz + nz.normal(0.3),
            if fz.abs() > 1.0 { fx / fz } else { 0.0 },
            if fz.abs() > 1.0 { -fy / -fz } else { 0.0 },
            28.0 + nz.normal(0.1),
            temp + 2.0 + nz.normal(0.3),
            temp + nz.normal(0.3),
            temp - 2.0 + nz.normal(0.3),
            86.5 + nz.normal(0.2),
            sr,
            if spec.cornering { 0.0 } else { kappa + nz.normal(0.0008) },
            0.0,
        ];
        for (k, v) in vals.iter().enumerate() {
            c[k].push(*v);
        }
    }
    let names = [
        "ET", "V", "N", "SA", "IA", "RL", "RE", "P", "FX", "FY", "FZ", "MX", "MZ", "NFX", "NFY", "RST", "TSTI", "TSTC",
        "TSTO", "AMBTMP", "SR", "SL",
    ];
    let units = units_of(spec.units);
    if matches!(spec.units, UnitStyle::Imperial | UnitStyle::Uscs) {
        // Written in US units: divide by the unit's size (temperatures: to °F).
        let scale = |c: &mut Vec<f64>, k: f64| c.iter_mut().for_each(|v| *v /= k);
        scale(&mut c[1], 1.609_344); // V mph
        scale(&mut c[5], 2.54); // RL in
        scale(&mut c[6], 2.54); // RE in
        scale(&mut c[7], 6.894_757_293_168); // P psi
        for k in [8, 9, 10] {
            scale(&mut c[k], 4.448_221_615_260_5); // lbf
        }
        for k in [15, 16, 17, 18] {
            c[k].iter_mut().for_each(|v| *v = *v * 9.0 / 5.0 + 32.0);
        }
        if spec.units == UnitStyle::Uscs {
            for k in [11, 12] {
                scale(&mut c[k], 4.448_221_615_260_5 * 0.3048); // lbf·ft
            }
            // AMBTMP is written honestly in °F here (86.5 stands for 30.3 °C).
        }
    }
    let mut t = ChannelTable {
        source: "fixture".into(),
        title: Some(if spec.older_round {
            format!("TIRF Data File: Project 1320; Run {}", 50 + spec.seed)
        } else {
            format!(
                "TIRF Data File: Project 0000; Run {:03}; synthetic {}; Tire_Name=Fixture 20.5x7.0-13, R25B; Rim_Width=7.0",
                spec.seed,
                if spec.cornering { "cornering" } else { "drive/brake/combined" }
            )
        }),
        tire_id: (!spec.older_round).then(|| "Fixture 20.5x7.0-13, R25B".into()),
        test_id: (!spec.older_round).then(|| {
            if spec.cornering { "Cornering, Various pressures".into() } else { "Drive/Brake/Combined, 12psi".into() }
        }),
        columns: Vec::new(),
    };
    for (k, (name, unit)) in names.iter().zip(units).enumerate() {
        if (*name == "SL" && (!spec.with_sl || spec.older_round)) || (*name == "NFX" && spec.older_round) {
            continue;
        }
        t.push(name, unit, std::mem::take(&mut c[k]));
    }
    t
}

/// The units line of a round.
fn units_of(style: UnitStyle) -> [&'static str; 22] {
    match style {
        UnitStyle::Ttc => [
            "s", "kph", "rpm", "deg", "deg", "cm", "cm", "kPa", "N", "N", "N", "N-m", "N-m", "none", "none", "degC",
            "degC", "degC", "degC", "degC", "none", "none",
        ],
        UnitStyle::LaterRound => [
            "sec", "kph", "rpm", "deg", "deg", "cm", "cm", "kPa", "N", "N", "N", "Nm", "Nm", "none", "none", "deg C",
            "deg C", "deg C", "deg C", "deg F", "none", "SAE",
        ],
        UnitStyle::Imperial => [
            "s", "mph", "rpm", "deg", "deg", "in", "in", "psi", "lbf", "lbf", "lbf", "N-m", "N-m", "none", "none",
            "degF", "degF", "degF", "degF", "degF", "none", "none",
        ],
        UnitStyle::Uscs => [
            "s", "mph", "rpm", "deg", "deg", "in", "in", "psi", "lb", "lb", "lb", "ft-lb", "ft-lb", "none", "none",
            "deg F", "deg F", "deg F", "deg F", "deg F", "none", "none",
        ],
    }
}

/// One quirk of a real test round, as a synthetic run that has it.
#[derive(Debug, Clone)]
pub struct QuirkFixture {
    /// File name (`.dat` or `.mat`).
    pub file: &'static str,
    /// The quirk, as `../shared/real-rig-data.md` describes it.
    pub quirk: &'static str,
    /// The run.
    pub spec: FixtureSpec,
    /// Where a `.mat` file's units go.
    pub mat_units: MatUnits,
}

/// Every quirk of other rounds' files, one synthetic run each (`tyrerig export quirk-fixtures`,
/// `tests/quirks.rs`).
pub fn quirk_fixtures() -> Vec<QuirkFixture> {
    let camber = CamberSweep { sa_deg: 1.8, cambers_deg: vec![0.0, 1.0, 2.0, 3.0, 4.0] };
    vec![
        QuirkFixture {
            file: "later_round_drive_brake.dat",
            quirk: "units spelled sec, Nm, deg C, deg F (AMBTMP) and SAE (SL)",
            spec: FixtureSpec { units: UnitStyle::LaterRound, ..FixtureSpec::drive_brake() },
            mat_units: MatUnits::TtcAssumed,
        },
        QuirkFixture {
            file: "later_round_cornering.mat",
            quirk: "a .mat file with no units at all",
            spec: FixtureSpec { units: UnitStyle::LaterRound, ..FixtureSpec::cornering() },
            mat_units: MatUnits::TtcAssumed,
        },
        QuirkFixture {
            file: "us_units_cornering.dat",
            quirk: "mph, in, psi, lbf, degF where the file says so",
            spec: FixtureSpec { units: UnitStyle::Imperial, ..FixtureSpec::cornering() },
            mat_units: MatUnits::TtcAssumed,
        },
        QuirkFixture {
            file: "older_round_cornering_camber.dat",
            quirk: "no SL/NFX/testid, SR not a slip ratio while cornering, load wandering ±15 %, camber sweeps at 1.8°",
            spec: FixtureSpec {
                older_round: true,
                fz_wander: 0.15,
                camber_sweep: Some(camber.clone()),
                ..FixtureSpec::cornering()
            },
            mat_units: MatUnits::TtcAssumed,
        },
        QuirkFixture {
            file: "load_wander_cornering.dat",
            quirk: "load wandering ±20 % around its setpoint during slip-angle sweeps, the next load set as a sweep ends",
            spec: FixtureSpec { fz_wander: 0.2, no_settle_after_sweeps: true, ..FixtureSpec::cornering() },
            mat_units: MatUnits::TtcAssumed,
        },
        QuirkFixture {
            file: "camber_sweeps_cornering.dat",
            quirk: "camber stepped 0–4° at a held slip angle of 1.8°, cornering at cambers 0 and 2°",
            spec: FixtureSpec { cambers_deg: vec![0.0, 2.0], camber_sweep: Some(camber), ..FixtureSpec::cornering() },
            mat_units: MatUnits::TtcAssumed,
        },
        QuirkFixture {
            file: "pure_longitudinal_065.dat",
            quirk: "pure longitudinal sweeps at slip angle 0 to slip ratio ±0.65",
            spec: pure_longitudinal(false),
            mat_units: MatUnits::TtcAssumed,
        },
        QuirkFixture {
            file: "older_round_pure_longitudinal_065.dat",
            quirk: "pure longitudinal to ±0.65 with only SR (the wheel driven and braked)",
            spec: pure_longitudinal(true),
            mat_units: MatUnits::TtcAssumed,
        },
        QuirkFixture {
            file: "warmup_drive_brake.dat",
            quirk: "five full warm-up sweeps at 1,100 N opening a drive/brake run, 1,100 N swept again later",
            spec: FixtureSpec { loads_n: vec![660.0, 1100.0], warmup_sweeps: 5, ..FixtureSpec::drive_brake() },
            mat_units: MatUnits::TtcAssumed,
        },
        QuirkFixture {
            file: "cold_start_cornering.dat",
            quirk: "a cornering run begun on a cold tyre (its tread 30 K below its running temperature), the first cell swept again at the end of the pressure",
            spec: FixtureSpec { cold_start_k: 30.0, ..FixtureSpec::cornering() },
            mat_units: MatUnits::TtcAssumed,
        },
        QuirkFixture {
            file: "uscs_cornering.mat",
            quirk: "TTC's USCS distribution (lb, psi, in, mph, ft-lb, deg F) with the units in the `channel` struct",
            spec: FixtureSpec { units: UnitStyle::Uscs, ..FixtureSpec::cornering() },
            mat_units: MatUnits::ChannelStruct,
        },
        QuirkFixture {
            file: "uscs_no_units_drive_brake.mat",
            quirk: "a USCS drive/brake run saved without any units (US customary told from the magnitudes)",
            spec: FixtureSpec { units: UnitStyle::Uscs, ..FixtureSpec::drive_brake() },
            mat_units: MatUnits::Unlisted,
        },
    ]
}

/// Pure longitudinal sweeps to ±0.65 at three loads, slip angle and camber 0.
pub fn pure_longitudinal(older_round: bool) -> FixtureSpec {
    FixtureSpec {
        loads_n: vec![1100.0, 660.0, 1540.0],
        cambers_deg: vec![0.0],
        slip_angles_deg: vec![0.0],
        kappa_reach: 0.65,
        sweep_s: 8.0,
        older_round,
        ..FixtureSpec::drive_brake()
    }
}
