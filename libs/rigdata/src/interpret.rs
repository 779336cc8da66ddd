//! A table's channels → the fitter's signals: each channel's role from its name, its unit from
//! the units line (or, where the file has none, the TTC unit checked against the magnitudes),
//! the sign convention from the data (SAE: FZ negative under load), and the conversion to ISO-W
//! axes and SI units.

use serde::Serialize;

use crate::channels::{Role, role_of};
use crate::error::{Place, ReadError, Warnings};
use crate::table::ChannelTable;
use crate::units::{self, Quantity, Unit};

/// Sign convention of a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
pub enum Convention {
    /// Decide from the data: FZ negative under load is SAE, positive is ISO-W.
    #[default]
    Auto,
    /// SAE (Calspan TTC): FY, FZ, slip angle, MY and MZ flip to reach ISO-W.
    Sae,
    /// Already ISO-W (TYDEX-W).
    IsoW,
}

impl Convention {
    /// Name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Convention::Auto => "auto",
            Convention::Sae => "SAE",
            Convention::IsoW => "ISO-W",
        }
    }
}

/// Where the file came from; decides the units assumed when a file gives none and the
/// convention expected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Family {
    /// Calspan / TTC (`.dat`, `.mat`): TTC units, SAE expected.
    Ttc,
    /// TYDEX: SI units, ISO-W expected.
    Tydex,
}

/// How one channel of the file was read.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelUse {
    /// Name as written.
    pub name: String,
    /// Unit as written (empty when the file gives none).
    pub unit_written: String,
    /// Unit the values were read in (the written one, or the one assumed).
    pub unit_read: String,
    /// What it became (`SLIPANGL [rad], sign flipped`, `not used`, …).
    pub used_as: String,
}

/// Which channel gave the slip ratio.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum KappaSource {
    /// `SL` / `LONGSLIP`.
    LoadedRadius,
    /// `SR` (no `SL` in the file): zeroed where the wheel rolls free.
    EffectiveRadius,
    /// None: slip ratio taken as zero (cornering data only).
    Absent,
}

/// The fitter's signals, one value per table row, ISO-W, SI (temperatures °C); NaN where a row
/// has no value, temperatures NaN when not recorded.
#[derive(Debug, Clone, Default)]
pub struct Signals {
    pub time_s: Vec<f64>,
    pub v_mps: Option<Vec<f64>>,
    pub omega_radps: Vec<f64>,
    pub alpha_rad: Vec<f64>,
    pub gamma_rad: Vec<f64>,
    pub rl_m: Vec<f64>,
    pub p_pa: Vec<f64>,
    pub fx_n: Vec<f64>,
    pub fy_n: Vec<f64>,
    pub fz_n: Vec<f64>,
    pub mx_nm: Vec<f64>,
    pub my_nm: Vec<f64>,
    pub mz_nm: Vec<f64>,
    pub kappa: Vec<f64>,
    pub temp_inner_c: Vec<f64>,
    pub temp_centre_c: Vec<f64>,
    pub temp_outer_c: Vec<f64>,
    pub road_temp_c: Vec<f64>,
    pub ambient_c: Option<Vec<f64>>,
}

/// The outcome of interpreting a table.
#[derive(Debug, Clone)]
pub struct Interpreted {
    /// The signals.
    pub signals: Signals,
    /// How each channel was read.
    pub channels: Vec<ChannelUse>,
    /// Convention used.
    pub convention: Convention,
    /// How it was decided.
    pub convention_basis: String,
    /// Slip-ratio source.
    pub kappa_source: KappaSource,
    /// Name of the channel the slip ratio came from.
    pub kappa_channel: Option<String>,
    /// Median sample period, s.
    pub period_s: f64,
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return None;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    Some(*m)
}

fn quantile_abs(v: &[f64], q: f64) -> Option<f64> {
    let mut a: Vec<f64> = v.iter().filter(|x| x.is_finite()).map(|x| x.abs()).collect();
    if a.is_empty() {
        return None;
    }
    let k = ((a.len() - 1) as f64 * q).round() as usize;
    let (_, m, _) = a.select_nth_unstable_by(k, f64::total_cmp);
    Some(*m)
}

/// Picks the unit of a channel the file gives none for: the TTC one unless the magnitudes say
/// otherwise (then with a warning).
fn assumed_unit(role: Role, values: &[f64], family: Family, ctx: &GuessContext) -> (String, Option<String>) {
    let default = match family {
        Family::Ttc => role.ttc_unit(),
        Family::Tydex => match role.quantity() {
            Quantity::Angle => "rad",
            Quantity::Speed => "m/s",
            Quantity::AngularSpeed => "rad/s",
            Quantity::Length => "m",
            Quantity::Pressure => "Pa",
            q => q.target_unit(),
        },
    };
    if family == Family::Ttc
        && let Some(us) = &ctx.us_customary
        && let Some(u) = us.unit_of(role.quantity())
    {
        return (u.to_owned(), None);
    }
    let med = median(values.iter().map(|v| v.abs()).filter(|v| *v > 0.0).collect());
    let guess = |u: &str, why: String| (u.to_owned(), Some(why));
    match (role, med) {
        (Role::Pressure, Some(m)) if family == Family::Ttc => {
            if m >= 5_000.0 {
                guess("Pa", format!("median {m:.0} looks like Pa"))
            } else if m >= 50.0 {
                (default.into(), None)
            } else if m >= 3.0 {
                guess(
                    "psi",
                    format!("median {m:.1} looks like psi (as kPa it would be {m:.1} kPa, too low for a tyre)"),
                )
            } else if m >= 0.3 {
                guess("bar", format!("median {m:.2} looks like bar"))
            } else {
                (default.into(), None)
            }
        }
        (Role::LoadedRadius, Some(m)) if family == Family::Ttc => {
            if m < 1.0 {
                guess("m", format!("median {m:.3} looks like metres"))
            } else if m > 100.0 {
                guess("mm", format!("median {m:.0} looks like millimetres"))
            } else {
                (default.into(), None)
            }
        }
        (Role::SlipAngle, _) if family == Family::Ttc => {
            let top = quantile_abs(values, 1.0).unwrap_or(0.0);
            let p98 = quantile_abs(values, 0.98).unwrap_or(0.0);
            if top <= 0.4 && p98 >= 0.1 {
                guess("rad", format!("largest |value| {top:.3} with sweeps looks like radians"))
            } else {
                (default.into(), None)
            }
        }
        (Role::RoadSpeed, Some(m)) if family == Family::Ttc => match ctx.rolling_mps {
            // Road speed against wheel speed × loaded radius: kph reads 3.6 times the m/s value.
            Some(r) if r > 0.5 && (m / r - 1.0).abs() < (m / r / 3.6 - 1.0).abs() => {
                guess("m/s", format!("median {m:.2} matches wheel speed × loaded radius ({r:.2} m/s) as m/s"))
            }
            _ => (default.into(), None),
        },
        (Role::Fz, _) => {
            let p98 = quantile_abs(values, 0.98).unwrap_or(0.0);
            if p98 > 0.0 && p98 < 20.0 && family == Family::Ttc {
                guess("kN", format!("98th percentile |FZ| {p98:.2} looks like kN"))
            } else {
                (default.into(), None)
            }
        }
        _ => (default.into(), None),
    }
}

/// What the whole file says about the units it does not give.
struct GuessContext {
    /// Rough rolling speed from wheel speed and loaded radius, used to tell kph from m/s.
    rolling_mps: Option<f64>,
    /// The file is in US customary units (TTC distributes every run in SI and in "USCS").
    us_customary: Option<UsCustomary>,
}

/// A run saved in US customary units without its units: lbf, psi, in, mph, °F, and moments in
/// lbf·ft (or lbf·in where the moment arms say so).
#[derive(Debug, Clone)]
struct UsCustomary {
    moment_unit: &'static str,
    why: String,
}

impl UsCustomary {
    fn unit_of(&self, q: Quantity) -> Option<&'static str> {
        Some(match q {
            Quantity::Speed => "mph",
            Quantity::Length => "in",
            Quantity::Pressure => "psi",
            Quantity::Force => "lbf",
            Quantity::Moment => self.moment_unit,
            Quantity::Temperature => "degF",
            _ => return None,
        })
    }

    /// Judges from the unitless columns: road speed against wheel speed × loaded radius (25 mph
    /// with a 10 in radius and 40 kph with 25 cm roll alike, at 330 and 425 rpm), or, without
    /// those, a pressure in psi with a radius in inches. Moment arms (|MZ| against |FY|, both
    /// 98th percentiles) tell lbf·ft (a trail of 0.02–0.15 ft) from lbf·in (0.2–2 in).
    fn detect(table: &ChannelTable, col: impl Fn(Role) -> Option<usize>) -> Option<UsCustomary> {
        let unitless = |r: Role| col(r).map(|i| &table.columns[i]).filter(|c| c.unit.trim().is_empty());
        let med = |r: Role| unitless(r).and_then(|c| median(c.values.iter().map(|v| v.abs()).collect()));
        let (rl, p) = (med(Role::LoadedRadius)?, med(Role::Pressure));
        let why = match (med(Role::WheelSpeed), med(Role::RoadSpeed)) {
            (Some(rpm), Some(v)) if rpm > 10.0 && v > 1.0 => {
                let omega = rpm * std::f64::consts::PI / 30.0;
                let miss = |rl_m: f64, v_mps: f64| (omega * rl_m / v_mps).ln().abs();
                let (us, si) = (miss(rl * 0.0254, v * 0.447_04), miss(rl / 100.0, v / 3.6));
                if us >= si.min(0.25) {
                    return None;
                }
                format!(
                    "road speed {v:.1} matches wheel speed {rpm:.0} rpm × loaded radius {rl:.2} as mph and inches, not as kph and cm"
                )
            }
            _ => match p {
                Some(p) if (3.0..50.0).contains(&p) && (5.0..17.0).contains(&rl) => {
                    format!("pressure median {p:.1} looks like psi and loaded radius median {rl:.2} like inches")
                }
                _ => return None,
            },
        };
        let p98 = |r: Role| unitless(r).and_then(|c| quantile_abs(&c.values, 0.98));
        let moment_unit = match (p98(Role::Mz), p98(Role::Fy)) {
            (Some(mz), Some(fy)) if fy > 0.0 && mz / fy > 0.25 => "lbf-in",
            _ => "lbf-ft",
        };
        Some(UsCustomary { moment_unit, why })
    }
}

/// Reads a table into signals. `family` sets the units assumed where the file has none.
pub fn interpret(
    table: &ChannelTable,
    family: Family,
    convention: Convention,
    warn: &mut Warnings,
) -> Result<Interpreted, ReadError> {
    let file = table.source.as_str();
    let n = table.rows();
    // Which column plays which role: the first column of a role wins.
    let mut by_role: Vec<(Role, usize)> = Vec::new();
    for (i, c) in table.columns.iter().enumerate() {
        if let Some(r) = role_of(&c.name) {
            if r == Role::Normalised {
                continue;
            }
            if by_role.iter().any(|(x, _)| *x == r) {
                warn.push(
                    "duplicate role",
                    Place::file(file).channel(&c.name),
                    format!("a second {} channel: not used", r.tydex_name()),
                );
            } else {
                by_role.push((r, i));
            }
        }
    }
    let col = |r: Role| by_role.iter().find(|(x, _)| *x == r).map(|(_, i)| &table.columns[*i]);
    for r in [Role::Fz, Role::SlipAngle] {
        if col(r).is_none() {
            let names = if r == Role::Fz { "FZ / FZW" } else { "SA / SLIPANGL" };
            return Err(ReadError::at(
                Place::file(file).channel(names),
                format!("channel missing: the fitter needs {}", r.tydex_name()),
            ));
        }
    }
    // Wheel speed × loaded radius, both in TTC units, for the speed-unit check.
    let rolling_mps = match (col(Role::WheelSpeed), col(Role::LoadedRadius)) {
        (Some(w), Some(r)) if w.unit.is_empty() || r.unit.is_empty() => {
            let omega = median(w.values.iter().map(|v| v.abs()).collect()).map(|x| x * std::f64::consts::PI / 30.0);
            let rl = median(r.values.iter().map(|v| v.abs()).collect()).map(|x| if x > 1.0 { x / 100.0 } else { x });
            omega.zip(rl).map(|(a, b)| a * b)
        }
        _ => None,
    };
    let us_customary = match family {
        Family::Ttc => UsCustomary::detect(table, |r| by_role.iter().find(|(x, _)| *x == r).map(|(_, i)| *i)),
        Family::Tydex => None,
    };
    if let Some(us) = &us_customary {
        warn.push(
            "US customary units",
            Place::file(file),
            format!(
                "no units in the file and {}: read as US customary (forces lbf, moments {}, lengths in, speed mph, pressure psi, temperatures degF)",
                us.why, us.moment_unit
            ),
        );
    }
    let ctx = GuessContext { rolling_mps, us_customary };
    let mut uses = Vec::with_capacity(table.columns.len());
    let mut units_of: Vec<(Role, Unit)> = Vec::new();
    let mut assumed = Vec::new();
    for c in &table.columns {
        let place = Place::file(file).channel(&c.name);
        let role = role_of(&c.name).filter(|r| {
            *r == Role::Normalised || by_role.iter().any(|(x, i)| x == r && table.columns[*i].name == c.name)
        });
        let Some(role) = role else {
            uses.push(ChannelUse {
                name: c.name.clone(),
                unit_written: c.unit.clone(),
                unit_read: c.unit.clone(),
                used_as: "not used".into(),
            });
            continue;
        };
        let shown_only = matches!(role, Role::EffectiveRadius | Role::Normalised | Role::AmbientTemp);
        let (unit_text, guessed) = if c.unit.trim().is_empty() {
            let (u, why) = assumed_unit(role, &c.values, family, &ctx);
            if let Some(why) = why {
                warn.push("unit guessed", place.clone(), format!("no unit in the file; {why}: read as {u}"));
            } else {
                assumed.push(format!("{} {u}", c.name));
            }
            (u, true)
        } else {
            (c.unit.trim().to_owned(), false)
        };
        let unit = match units::parse(&unit_text) {
            Some(u) if u.quantity == role.quantity() => u,
            Some(u) if shown_only => {
                warn.push(
                    "unit",
                    place,
                    format!(
                        "unit `{unit_text}` is a unit of {}, expected one of {}: channel not used",
                        u.quantity.name(),
                        role.quantity().name()
                    ),
                );
                uses.push(ChannelUse {
                    name: c.name.clone(),
                    unit_written: c.unit.clone(),
                    unit_read: unit_text,
                    used_as: "not used (wrong unit)".into(),
                });
                continue;
            }
            Some(u) => {
                return Err(ReadError::at(
                    place,
                    format!(
                        "unit `{unit_text}` is a unit of {}; {} needs a unit of {}",
                        u.quantity.name(),
                        c.name,
                        role.quantity().name()
                    ),
                ));
            }
            None if shown_only => {
                warn.push("unit", place.clone(), format!("unknown unit `{unit_text}`: channel not used"));
                uses.push(ChannelUse {
                    name: c.name.clone(),
                    unit_written: c.unit.clone(),
                    unit_read: unit_text,
                    used_as: "not used (unknown unit)".into(),
                });
                continue;
            }
            // A spelling we do not know on a channel the fitter needs: refusing a whole run
            // for it helps no one. Read it as if the file gave no unit (the TTC unit, checked
            // against the magnitudes) and say so loudly.
            None => {
                let (assumed_text, why) = assumed_unit(role, &c.values, family, &ctx);
                let Some(u) = units::parse(&assumed_text).filter(|u| u.quantity == role.quantity()) else {
                    return Err(ReadError::at(place, format!("unknown unit `{unit_text}`")));
                };
                warn.push(
                    "unknown unit",
                    place,
                    format!(
                        "unknown unit `{unit_text}` (known for a {}: {}): read as {assumed_text}{}; check the values",
                        role.quantity().name(),
                        known_units(role.quantity()),
                        why.map(|w| format!(" ({w})")).unwrap_or_default()
                    ),
                );
                units_of.push((role, u));
                uses.push(ChannelUse {
                    name: c.name.clone(),
                    unit_written: c.unit.clone(),
                    unit_read: assumed_text,
                    used_as: format!("{} [{}], unit assumed", role.tydex_name(), role.quantity().target_unit()),
                });
                continue;
            }
        };
        let _ = guessed;
        units_of.push((role, unit));
        if role == Role::SlipRatioEffective && col(Role::SlipRatio).is_some() {
            uses.push(ChannelUse {
                name: c.name.clone(),
                unit_written: c.unit.clone(),
                unit_read: unit_text,
                used_as: "not used (SL is the slip ratio)".into(),
            });
            continue;
        }
        uses.push(ChannelUse {
            name: c.name.clone(),
            unit_written: c.unit.clone(),
            unit_read: unit_text,
            used_as: if shown_only {
                role.tydex_name().into()
            } else {
                format!("{} [{}]", role.tydex_name(), role.quantity().target_unit())
            },
        });
    }
    if !assumed.is_empty() && ctx.us_customary.is_none() {
        warn.push(
            "units assumed",
            Place::file(file),
            format!(
                "no units in the file: TTC units assumed and checked against the magnitudes ({})",
                assumed.join(", ")
            ),
        );
    }
    let read = |r: Role| -> Option<Vec<f64>> {
        let c = col(r)?;
        let u = units_of.iter().find(|(x, _)| *x == r)?.1;
        Some(c.values.iter().map(|&v| u.to_target(v)).collect())
    };
    // Convention: FZ negative under load is SAE.
    let fz_raw = read(Role::Fz).unwrap_or_default();
    let p98 = quantile_abs(&fz_raw, 0.98).unwrap_or(0.0);
    let loaded_median = median(fz_raw.iter().copied().filter(|v| v.abs() > 0.2 * p98).collect());
    let expected = if family == Family::Ttc { Convention::Sae } else { Convention::IsoW };
    let (convention, basis) = match (convention, loaded_median) {
        (Convention::Auto, Some(m)) => {
            let c = if m < 0.0 { Convention::Sae } else { Convention::IsoW };
            let basis =
                format!("detected: FZ {} under load (median {m:.0} N)", if m < 0.0 { "negative" } else { "positive" });
            if c != expected {
                warn.push(
                    "convention",
                    Place::file(file).channel(&col(Role::Fz).map(|c| c.name.clone()).unwrap_or_default()),
                    format!(
                        "{basis}: read as {}, though {} files are usually {} (override with --convention)",
                        c.name(),
                        if family == Family::Ttc { "TTC" } else { "TYDEX" },
                        expected.name()
                    ),
                );
            }
            (c, basis)
        }
        (Convention::Auto, None) => (expected, format!("no loaded rows to judge from: {} assumed", expected.name())),
        (c, _) => (c, "given".to_owned()),
    };
    let sign = |r: Role| if convention == Convention::Sae && r.flips_sae_to_iso() { -1.0 } else { 1.0 };
    let get = |r: Role, missing: f64| -> Vec<f64> {
        match read(r) {
            Some(v) => {
                let s = sign(r);
                v.into_iter().map(|x| s * x).collect()
            }
            None => vec![missing; n],
        }
    };
    for (r, what) in [(Role::Fy, "FY"), (Role::Fx, "FX"), (Role::Mz, "MZ"), (Role::Pressure, "P")] {
        if col(r).is_none() {
            warn.push(
                "missing channel",
                Place::file(file).channel(what),
                format!("no {} channel: taken as 0", r.tydex_name()),
            );
        }
    }
    // Time: ET, else the row index at an assumed 100 Hz.
    let time_s = match read(Role::Time) {
        Some(t) => t,
        None => {
            warn.push("missing channel", Place::file(file).channel("ET"), "no time channel: rows taken as 100 Hz");
            (0..n).map(|i| i as f64 * 0.01).collect()
        }
    };
    let period_s = median(time_s.windows(2).map(|w| w[1] - w[0]).filter(|d| *d > 0.0).collect()).unwrap_or(0.01);
    // Slip ratio: SL, else SR.
    let (kappa_source, kappa_channel, kappa) = if let Some(c) = col(Role::SlipRatio) {
        (KappaSource::LoadedRadius, Some(c.name.clone()), get(Role::SlipRatio, 0.0))
    } else if let Some(c) = col(Role::SlipRatioEffective) {
        warn.push(
            "SR used",
            Place::file(file).channel(&c.name),
            "no SL channel: the slip ratio comes from SR (effective radius), zeroed wherever the wheel rolls free",
        );
        (KappaSource::EffectiveRadius, Some(c.name.clone()), get(Role::SlipRatioEffective, 0.0))
    } else {
        (KappaSource::Absent, None, vec![0.0; n])
    };
    // Ambient temperature labelled °C but around 85–90: °F.
    let ambient_c = read(Role::AmbientTemp).map(|mut a| {
        let unit_is_c = units_of.iter().any(|(r, u)| *r == Role::AmbientTemp && u.offset == 0.0 && u.scale == 1.0);
        if let Some(m) = median(a.clone())
            && unit_is_c
            && (60.0..=110.0).contains(&m)
        {
            warn.push(
                "degF as degC",
                Place::file(file).channel(&col(Role::AmbientTemp).map(|c| c.name.clone()).unwrap_or_default()),
                format!(
                    "ambient temperature median {m:.1} labelled degC is surely degF: converted ({:.1} degC)",
                    (m - 32.0) * 5.0 / 9.0
                ),
            );
            for x in &mut a {
                *x = (*x - 32.0) * 5.0 / 9.0;
            }
        }
        a
    });
    let signals = Signals {
        time_s,
        v_mps: read(Role::RoadSpeed),
        omega_radps: get(Role::WheelSpeed, 0.0).into_iter().map(f64::abs).collect(),
        alpha_rad: get(Role::SlipAngle, f64::NAN),
        gamma_rad: get(Role::Inclination, 0.0),
        rl_m: get(Role::LoadedRadius, 0.0),
        p_pa: get(Role::Pressure, 0.0),
        fx_n: get(Role::Fx, 0.0),
        fy_n: get(Role::Fy, 0.0),
        fz_n: get(Role::Fz, f64::NAN),
        mx_nm: get(Role::Mx, 0.0),
        my_nm: get(Role::My, 0.0),
        mz_nm: get(Role::Mz, 0.0),
        kappa,
        temp_inner_c: get(Role::TreadTempInner, f64::NAN),
        temp_centre_c: get(Role::TreadTempCentre, f64::NAN),
        temp_outer_c: get(Role::TreadTempOuter, f64::NAN),
        road_temp_c: get(Role::RoadTemp, f64::NAN),
        ambient_c,
    };
    for u in &mut uses {
        if let Some(r) = role_of(&u.name)
            && sign(r) < 0.0
            && u.used_as.contains('[')
        {
            u.used_as.push_str(", sign flipped");
        }
    }
    Ok(Interpreted {
        signals,
        channels: uses,
        convention,
        convention_basis: basis,
        kappa_source,
        kappa_channel,
        period_s,
    })
}

fn known_units(q: Quantity) -> &'static str {
    match q {
        Quantity::Time => "s, ms",
        Quantity::Speed => "kph, km/h, m/s, mph",
        Quantity::AngularSpeed => "rpm, rad/s, deg/s",
        Quantity::Angle => "deg, rad",
        Quantity::Length => "mm, cm, m, in",
        Quantity::Pressure => "Pa, kPa, bar, psi",
        Quantity::Force => "N, kN, lbf",
        Quantity::Moment => "N-m, Nm, lbf-ft, lbf-in",
        Quantity::Ratio => "none, -, %",
        Quantity::Temperature => "degC, degF, K",
    }
}
