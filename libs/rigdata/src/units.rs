//! Units as rigs write them, and their conversion to the fitter's units: SI, except angles in
//! radians (SI anyway) and temperatures in °C (the fitter's `Sample` keeps °C).

use serde::Serialize;

/// What a channel measures; decides which units it may carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Quantity {
    /// s.
    Time,
    /// m/s.
    Speed,
    /// rad/s.
    AngularSpeed,
    /// rad.
    Angle,
    /// m.
    Length,
    /// Pa.
    Pressure,
    /// N.
    Force,
    /// N·m.
    Moment,
    /// Dimensionless (slip ratio, normalised force).
    Ratio,
    /// °C.
    Temperature,
}

impl Quantity {
    /// The fitter's unit for this quantity, as printed.
    pub fn target_unit(self) -> &'static str {
        match self {
            Quantity::Time => "s",
            Quantity::Speed => "m/s",
            Quantity::AngularSpeed => "rad/s",
            Quantity::Angle => "rad",
            Quantity::Length => "m",
            Quantity::Pressure => "Pa",
            Quantity::Force => "N",
            Quantity::Moment => "N·m",
            Quantity::Ratio => "-",
            Quantity::Temperature => "degC",
        }
    }

    /// Name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Time => "time",
            Quantity::Speed => "speed",
            Quantity::AngularSpeed => "angular speed",
            Quantity::Angle => "angle",
            Quantity::Length => "length",
            Quantity::Pressure => "pressure",
            Quantity::Force => "force",
            Quantity::Moment => "moment",
            Quantity::Ratio => "ratio",
            Quantity::Temperature => "temperature",
        }
    }
}

/// A unit: `fitter value = written value × scale + offset`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Unit {
    /// What it measures.
    pub quantity: Quantity,
    /// Scale to the fitter's unit.
    pub scale: f64,
    /// Offset after scaling (temperatures only).
    pub offset: f64,
}

impl Unit {
    /// Converts a written value.
    pub fn to_target(self, v: f64) -> f64 {
        v * self.scale + self.offset
    }

    /// Converts a value in the fitter's unit back to this unit.
    pub fn from_target(self, v: f64) -> f64 {
        (v - self.offset) / self.scale
    }
}

const LBF_N: f64 = 4.448_221_615_260_5;
const PSI_PA: f64 = 6_894.757_293_168;
const FT_M: f64 = 0.3048;
const IN_M: f64 = 0.0254;

/// Parses a unit as written (`kph`, `N-m`, `degC`, `[kPa]`, …; case and surrounding brackets
/// ignored). `None` when the unit is unknown. An empty unit is not parsed here: the caller
/// decides what a missing unit means.
pub fn parse(text: &str) -> Option<Unit> {
    use Quantity::*;
    let t = text.trim().trim_matches(|c| matches!(c, '[' | ']' | '(' | ')')).trim();
    let lower = t.to_lowercase().replace(['°', 'º'], "deg").replace(' ', "");
    let compound = us_compound(&lower);
    let (quantity, scale, offset) = match compound.as_deref().unwrap_or(lower.as_str()) {
        "s" | "sec" | "secs" | "second" | "seconds" => (Time, 1.0, 0.0),
        "ms" => (Time, 1e-3, 0.0),
        "kph" | "km/h" | "kmh" | "km/hr" | "kmph" => (Speed, 1.0 / 3.6, 0.0),
        "m/s" | "mps" | "m/sec" => (Speed, 1.0, 0.0),
        "mph" | "mi/h" | "mi/hr" | "mile/h" => (Speed, 0.447_04, 0.0),
        "rpm" | "1/min" | "rev/min" | "u/min" => (AngularSpeed, std::f64::consts::PI / 30.0, 0.0),
        "rad/s" | "rad/sec" | "1/s" => (AngularSpeed, 1.0, 0.0),
        "deg/s" | "deg/sec" => (AngularSpeed, std::f64::consts::PI / 180.0, 0.0),
        "deg" | "degree" | "degrees" | "grad" => (Angle, std::f64::consts::PI / 180.0, 0.0),
        "rad" | "radian" | "radians" => (Angle, 1.0, 0.0),
        "mm" => (Length, 1e-3, 0.0),
        "cm" => (Length, 1e-2, 0.0),
        "m" => (Length, 1.0, 0.0),
        "in" | "inch" | "inches" => (Length, IN_M, 0.0),
        "pa" => (Pressure, 1.0, 0.0),
        "hpa" | "mbar" => (Pressure, 100.0, 0.0),
        "kpa" => (Pressure, 1e3, 0.0),
        "mpa" => (Pressure, 1e6, 0.0),
        "bar" => (Pressure, 1e5, 0.0),
        "psi" | "psig" | "lbf/in2" | "lb/in2" | "lb/in^2" => (Pressure, PSI_PA, 0.0),
        "n" => (Force, 1.0, 0.0),
        "kn" => (Force, 1e3, 0.0),
        "lbf" | "lb" | "lbs" => (Force, LBF_N, 0.0),
        "n-m" | "nm" | "n*m" | "n.m" | "n·m" | "n_m" => (Moment, 1.0, 0.0),
        "knm" | "kn-m" | "kn*m" | "kn.m" => (Moment, 1e3, 0.0),
        "lb-ft" => (Moment, LBF_N * FT_M, 0.0),
        "lb-in" => (Moment, LBF_N * IN_M, 0.0),
        // `SAE` is how some TTC rounds label SL: the SAE slip-ratio definition, a plain ratio.
        "none" | "-" | "1" | "ratio" | "nd" | "n/a" | "sae" => (Ratio, 1.0, 0.0),
        "%" | "percent" => (Ratio, 0.01, 0.0),
        "degc" | "c" | "celsius" | "degcelsius" => (Temperature, 1.0, 0.0),
        "degf" | "f" | "fahrenheit" => (Temperature, 5.0 / 9.0, -32.0 * 5.0 / 9.0),
        "k" | "kelvin" => (Temperature, 1.0, -273.15),
        _ => return None,
    };
    Some(Unit { quantity, scale, offset })
}

/// US force and moment units come in many spellings (`lbs`, `lbf`, `ft-lb`, `ft*lbs`, `lb.ft`,
/// `in lbs`): the force part is reduced to `lb` and a moment to `lb-ft` / `lb-in`, whatever the
/// order and the separator. `None` for anything else.
fn us_compound(lower: &str) -> Option<String> {
    let parts: Vec<&str> = lower.split(['-', '*', '.', '·', '_']).filter(|p| !p.is_empty()).collect();
    let is_lb = |p: &str| matches!(p, "lb" | "lbs" | "lbf");
    match parts.as_slice() {
        [p] if is_lb(p) => Some("lb".into()),
        [p] => {
            // Written without a separator: `ftlb`, `lbfft`, `inlbs`, `lbin`.
            ["lbf", "lbs", "lb"].iter().find_map(|lb| moment_of(p.strip_prefix(lb).or_else(|| p.strip_suffix(lb))?))
        }
        [a, b] if is_lb(a) => moment_of(b),
        [a, b] if is_lb(b) => moment_of(a),
        _ => None,
    }
}

fn moment_of(arm: &str) -> Option<String> {
    match arm {
        "ft" | "feet" | "foot" => Some("lb-ft".into()),
        "in" | "inch" | "inches" => Some("lb-in".into()),
        _ => None,
    }
}

/// The SI scale and offset TYDEX expects in a channel's conversion factor for a written unit
/// (`value × factor + offset` = SI): the same as [`parse`] except temperatures, whose SI unit is
/// the kelvin.
pub fn tydex_si_factor(unit: &Unit) -> (f64, f64) {
    if unit.quantity == Quantity::Temperature { (unit.scale, unit.offset + 273.15) } else { (unit.scale, unit.offset) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ttc_units_convert_to_the_fitters() {
        let close = |a: f64, b: f64| (a - b).abs() < 1e-9 * b.abs().max(1.0);
        let conv = |u: &str, v: f64| parse(u).unwrap().to_target(v);
        assert!(close(conv("kph", 36.0), 10.0));
        assert!(close(conv("rpm", 30.0), std::f64::consts::PI));
        assert!(close(conv("cm", 25.0), 0.25));
        assert!(close(conv("kPa", 83.0), 83_000.0));
        assert!(close(conv("psi", 12.0), 82_737.087_518));
        assert!(close(conv("lbf", 100.0), 444.822_161_526));
        assert!(close(conv("N-m", 5.0), 5.0));
        assert!(close(conv("lbf-ft", 1.0), 1.355_817_948));
        assert!(close(conv("deg", 180.0), std::f64::consts::PI));
        assert!(close(conv("degF", 212.0), 100.0));
        assert!(close(conv("[degC]", 40.0), 40.0));
        assert!(close(conv("°C", 40.0), 40.0));
        assert_eq!(parse("none").unwrap().quantity, Quantity::Ratio);
        assert_eq!(parse("-").unwrap().quantity, Quantity::Ratio);
        // Spellings of other test rounds.
        assert_eq!(parse("SAE").unwrap(), parse("none").unwrap());
        assert_eq!(parse("sec").unwrap(), parse("s").unwrap());
        assert_eq!(parse("Nm").unwrap(), parse("N-m").unwrap());
        assert_eq!(parse("deg C").unwrap(), parse("degC").unwrap());
        assert!(close(conv("deg F", 86.0), 30.0));
        assert!(close(conv("mph", 25.0), 11.176));
        assert!(close(conv("in", 10.0), 0.254));
        assert!(parse("furlongs").is_none());
        // US force and moment spellings, any order and separator.
        for f in ["lb", "lbs", "LBF", "lbf"] {
            assert!(close(conv(f, 100.0), 444.822_161_526), "{f}");
        }
        for m in ["ft-lb", "ft*lb", "ft-lbs", "lb-ft", "lbf-ft", "ft lbf", "ftlb", "lbft", "lb.ft", "ft-lbf"] {
            assert!(close(conv(m, 1.0), 1.355_817_948), "{m}");
        }
        for m in ["in-lb", "in*lbs", "lb-in", "inlb", "lbf-in", "in lbs"] {
            assert!(close(conv(m, 12.0), 1.355_817_948), "{m}");
        }
        assert!(close(conv("psig", 12.0), 82_737.087_518));
        assert!(parse("lb-furlong").is_none());
        assert!(parse("x").is_none());
        let u = parse("bar").unwrap();
        assert!(close(u.from_target(u.to_target(1.3)), 1.3));
    }
}
