//! How far a sweep reaches into the operating envelope, and where the data of a slot stop short
//! of what its sweeps could reach.
//!
//! The value of a sweep is a variance reduction of the linearised model, and variance says
//! nothing about model-form error where the data end: an MF model fitted up to 1.5·Fz0 is sure of
//! itself at 1.8·Fz0, and may be wrong there. With [`crate::AdaptiveConfig::cover_envelope`] the
//! planner makes a slot's data reach every extreme of the envelope that one of its sweeps
//! reaches before the slot closes ([`crate::Planner`]), so the fitted model's tested range (the
//! `.tir` limits) is the procedure's.

use procedure::Setpoint;
use serde::{Deserialize, Serialize};

/// The reach of a set of points on each axis of the envelope.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Extent {
    /// Lowest vertical load \[N\].
    pub fz_min_n: f64,
    /// Highest vertical load \[N\].
    pub fz_max_n: f64,
    /// Largest |slip angle| \[deg\].
    pub slip_angle_abs_max_deg: f64,
    /// Largest |slip ratio| \[-\].
    pub slip_ratio_abs_max: f64,
    /// Lowest camber \[deg\].
    pub camber_min_deg: f64,
    /// Highest camber \[deg\].
    pub camber_max_deg: f64,
}

/// How much further than the data a sweep must reach to count as new ground: 5 % of the data's
/// highest load, 1° of slip angle, 0.02 of slip ratio, 0.5° of camber (below these the fit
/// interpolates as well as it extrapolates).
const LOAD_MARGIN: f64 = 0.05;
const SLIP_ANGLE_MARGIN_DEG: f64 = 1.0;
const SLIP_RATIO_MARGIN: f64 = 0.02;
const CAMBER_MARGIN_DEG: f64 = 0.5;

impl Extent {
    /// The reach of `points`; `None` without points.
    pub fn of(points: &[Setpoint]) -> Option<Self> {
        let first = points.first()?;
        let mut e = Extent {
            fz_min_n: first.fz_n,
            fz_max_n: first.fz_n,
            slip_angle_abs_max_deg: first.slip_angle_deg.abs(),
            slip_ratio_abs_max: first.slip_ratio.abs(),
            camber_min_deg: first.camber_deg,
            camber_max_deg: first.camber_deg,
        };
        for p in &points[1..] {
            e.fz_min_n = e.fz_min_n.min(p.fz_n);
            e.fz_max_n = e.fz_max_n.max(p.fz_n);
            e.slip_angle_abs_max_deg = e.slip_angle_abs_max_deg.max(p.slip_angle_deg.abs());
            e.slip_ratio_abs_max = e.slip_ratio_abs_max.max(p.slip_ratio.abs());
            e.camber_min_deg = e.camber_min_deg.min(p.camber_deg);
            e.camber_max_deg = e.camber_max_deg.max(p.camber_deg);
        }
        Some(e)
    }

    /// The reach of both.
    pub fn union(self, o: Extent) -> Extent {
        Extent {
            fz_min_n: self.fz_min_n.min(o.fz_min_n),
            fz_max_n: self.fz_max_n.max(o.fz_max_n),
            slip_angle_abs_max_deg: self.slip_angle_abs_max_deg.max(o.slip_angle_abs_max_deg),
            slip_ratio_abs_max: self.slip_ratio_abs_max.max(o.slip_ratio_abs_max),
            camber_min_deg: self.camber_min_deg.min(o.camber_min_deg),
            camber_max_deg: self.camber_max_deg.max(o.camber_max_deg),
        }
    }

    /// Where `self` reaches beyond `data` by more than the margins, in words (empty: nowhere).
    pub fn beyond(&self, data: &Extent) -> Vec<String> {
        let mut out = Vec::new();
        let load_margin = LOAD_MARGIN * data.fz_max_n.abs();
        if self.fz_max_n > data.fz_max_n + load_margin {
            out.push(format!("load to {:.0} N (data to {:.0} N)", self.fz_max_n, data.fz_max_n));
        }
        if self.fz_min_n < data.fz_min_n - load_margin {
            out.push(format!("load down to {:.0} N (data down to {:.0} N)", self.fz_min_n, data.fz_min_n));
        }
        if self.slip_angle_abs_max_deg > data.slip_angle_abs_max_deg + SLIP_ANGLE_MARGIN_DEG {
            out.push(format!(
                "slip angle to {:.1}° (data to {:.1}°)",
                self.slip_angle_abs_max_deg, data.slip_angle_abs_max_deg
            ));
        }
        if self.slip_ratio_abs_max > data.slip_ratio_abs_max + SLIP_RATIO_MARGIN {
            out.push(format!("slip ratio to {:.2} (data to {:.2})", self.slip_ratio_abs_max, data.slip_ratio_abs_max));
        }
        if self.camber_max_deg > data.camber_max_deg + CAMBER_MARGIN_DEG {
            out.push(format!("camber to {:.1}° (data to {:.1}°)", self.camber_max_deg, data.camber_max_deg));
        }
        if self.camber_min_deg < data.camber_min_deg - CAMBER_MARGIN_DEG {
            out.push(format!("camber down to {:.1}° (data down to {:.1}°)", self.camber_min_deg, data.camber_min_deg));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sp(fz_n: f64, slip_angle_deg: f64, camber_deg: f64) -> Setpoint {
        Setpoint { fz_n, slip_angle_deg, camber_deg, ..Setpoint::default() }
    }

    #[test]
    fn reach_and_what_lies_beyond_it() {
        let data = Extent::of(&[sp(3000.0, -12.0, 0.0), sp(9000.0, 12.0, 1.8)]).unwrap();
        assert_eq!(data.fz_max_n, 9000.0);
        assert_eq!(data.slip_angle_abs_max_deg, 12.0);
        // Within the margins: nothing new.
        let near = Extent::of(&[sp(9400.0, 12.9, 2.2)]).unwrap();
        assert!(near.beyond(&data).is_empty(), "{:?}", near.beyond(&data));
        // A vertical-load sweep to 12 kN from 1.35 kN reaches new ground at both ends of load.
        let vl = Extent::of(&[sp(1350.0, 18.0, 0.0), sp(12000.0, 18.0, 0.0)]).unwrap();
        let b = vl.beyond(&data);
        assert_eq!(b.len(), 3, "{b:?}");
        assert!(b[0].starts_with("load to 12000 N"));
        assert!(b.iter().any(|s| s.starts_with("slip angle to 18.0°")));
        // Once run, the union covers it.
        assert!(vl.beyond(&data.union(vl)).is_empty());
        assert!(Extent::of(&[]).is_none());
    }
}
