//! `foxglove/model`: the live fit's `model/state` as a control room reads it — which stages are
//! identified and how well they fit (a Table panel), and each channel's predicted curve with its
//! 95 % band at the nominal operating point (Plot panels, slip on the x axis): how sure the
//! model already is, and where.

use serde::Serialize;
use tyre_msgs::{ModelMap, ModelStage, ModelState};

/// `foxglove/model`.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ModelView {
    /// Rig time of the sweep end that triggered the update [s].
    pub rig_time_s: f64,
    pub update_index: u32,
    pub final_update: bool,
    pub last_sweep: String,
    pub update_wall_s: f64,
    /// Why the update failed (empty when it did not; the previous model stands).
    pub error: String,
    /// "k / n stages identified".
    pub identified: String,
    pub stages: Vec<StageRow>,
    /// One band per map channel (FYW, FX, MZW).
    pub bands: Vec<Band>,
}

/// One stage as a table row.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct StageRow {
    pub stage: String,
    pub channel: String,
    /// `waiting`, `fitting` or `identified`.
    pub status: String,
    /// Why it is not identified yet.
    pub reason: String,
    pub points: u32,
    pub nrmse_pct: f64,
    /// Coefficients fitted.
    pub coefficients: u32,
    /// The largest relative standard deviation of a fitted coefficient, 100·σ/|value| [%]
    /// (NaN while waiting or when none is finite).
    pub worst_relative_std_pct: f64,
}

/// A channel's prediction over slip at the grid point nearest the nominal condition (middle
/// load, camber nearest 0, middle pressure), with the band of the mean (±1.96·σ).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Band {
    pub channel: String,
    /// `slip_angle_deg` or `slip_ratio`.
    pub slip_axis: String,
    pub fz_n: f64,
    pub camber_deg: f64,
    pub pressure_pa: f64,
    pub slip: Vec<f64>,
    pub value: Vec<f64>,
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
    /// 1σ of the prediction (NaN while a stage it depends on is not fitted).
    pub std: Vec<f64>,
    /// True where the slice leaves the tested envelope: the curve there is extrapolated.
    pub extrapolated: Vec<bool>,
    /// The prediction where the data reached, NaN where it is extrapolated (drawn over `value`,
    /// a Plot panel shows the measured part solid and breaks it where the model guesses).
    pub value_tested: Vec<f64>,
    /// The band for a repeat measurement (± this holds 95 % of the stage's held-out residuals;
    /// NaN when the state has none: before the stage is fitted, or recorded before it existed).
    pub repeat_band: f64,
    /// `value` ∓ `repeat_band`: where a new measurement is expected.
    pub repeat_lower: Vec<f64>,
    pub repeat_upper: Vec<f64>,
}

impl ModelView {
    /// The view of one `model/state` message.
    pub fn of(st: &ModelState) -> Self {
        let identified = st.stages.iter().filter(|s| s.status == ModelStage::IDENTIFIED).count();
        Self {
            rig_time_s: st.header.stamp.as_secs_f64(),
            update_index: st.update_index,
            final_update: st.final_update,
            last_sweep: st.last_sweep.clone(),
            update_wall_s: st.update_wall_s,
            error: st.error.clone(),
            identified: format!("{identified} / {} stages identified", st.stages.len()),
            stages: st.stages.iter().map(stage_row).collect(),
            bands: st.maps.iter().enumerate().filter_map(|(k, m)| band(st, k, m)).collect(),
        }
    }
}

fn stage_row(s: &ModelStage) -> StageRow {
    let worst = s
        .coefficients
        .iter()
        .filter(|c| c.std.is_finite() && c.value != 0.0)
        .map(|c| 100.0 * c.std / c.value.abs())
        .fold(f64::NAN, f64::max);
    StageRow {
        stage: s.stage.clone(),
        channel: s.channel.clone(),
        status: ModelStage::status_name(s.status).to_owned(),
        reason: s.status_reason.clone(),
        points: s.points,
        nrmse_pct: s.nrmse_pct,
        coefficients: s.coefficients.len() as u32,
        worst_relative_std_pct: worst,
    }
}

/// Index of the value in `axis` nearest `target` (0 for an empty axis).
fn nearest(axis: &[f64], target: f64) -> usize {
    axis.iter().enumerate().min_by(|a, b| (a.1 - target).abs().total_cmp(&(b.1 - target).abs())).map_or(0, |(i, _)| i)
}

/// The slice of `map` over slip at the nominal grid point; `None` when the map does not have the
/// grid's size (a malformed message: the view is skipped, not the node).
fn band(st: &ModelState, k: usize, map: &ModelMap) -> Option<Band> {
    let slip = match map.slip_axis.as_str() {
        "slip_ratio" => &st.grid_slip_ratio,
        _ => &st.grid_slip_angle_deg,
    };
    let (nl, ns, nc, np) = (st.grid_fz_n.len(), slip.len(), st.grid_camber_deg.len(), st.grid_pressure_pa.len());
    let n = nl * ns * nc * np;
    if n == 0 || map.value.len() != n || map.std.len() != n {
        return None;
    }
    let il = nl / 2;
    let ic = nearest(&st.grid_camber_deg, 0.0);
    let ip = np / 2;
    // Load slowest, then slip, camber, pressure fastest.
    let at = |is: usize| ((il * ns + is) * nc + ic) * np + ip;
    let value: Vec<f64> = (0..ns).map(|is| map.value[at(is)]).collect();
    let std: Vec<f64> = (0..ns).map(|is| map.std[at(is)]).collect();
    // A state from before the flag existed has none: nothing is marked extrapolated.
    let extrapolated: Vec<bool> = (0..ns).map(|is| st.extrapolated(k, at(is))).collect();
    let value_tested = value.iter().zip(&extrapolated).map(|(v, x)| if *x { f64::NAN } else { *v }).collect();
    let repeat_band = st.repeat_band(k);
    Some(Band {
        repeat_lower: value.iter().map(|v| v - repeat_band).collect(),
        repeat_upper: value.iter().map(|v| v + repeat_band).collect(),
        repeat_band,
        channel: map.channel.clone(),
        slip_axis: map.slip_axis.clone(),
        fz_n: st.grid_fz_n[il],
        camber_deg: st.grid_camber_deg[ic],
        pressure_pa: st.grid_pressure_pa[ip],
        slip: slip.clone(),
        lower: value.iter().zip(&std).map(|(v, s)| v - 1.96 * s).collect(),
        upper: value.iter().zip(&std).map(|(v, s)| v + 1.96 * s).collect(),
        value,
        std,
        extrapolated,
        value_tested,
    })
}

pub(crate) const MODEL_SCHEMA: &str = r#"{"type":"object","properties":{
"rig_time_s":{"type":"number"},"update_index":{"type":"integer"},"final_update":{"type":"boolean"},
"last_sweep":{"type":"string"},"update_wall_s":{"type":"number"},"error":{"type":"string"},
"identified":{"type":"string"},
"stages":{"type":"array","items":{"type":"object","properties":{"stage":{"type":"string"},
"channel":{"type":"string"},"status":{"type":"string"},"reason":{"type":"string"},"points":{"type":"integer"},
"nrmse_pct":{"type":"number"},"coefficients":{"type":"integer"},"worst_relative_std_pct":{"type":"number"}}}},
"bands":{"type":"array","items":{"type":"object","properties":{"channel":{"type":"string"},
"slip_axis":{"type":"string"},"fz_n":{"type":"number"},"camber_deg":{"type":"number"},
"pressure_pa":{"type":"number"},"slip":{"type":"array","items":{"type":"number"}},
"value":{"type":"array","items":{"type":"number"}},"lower":{"type":"array","items":{"type":"number"}},
"upper":{"type":"array","items":{"type":"number"}},"std":{"type":"array","items":{"type":"number"}},
"extrapolated":{"type":"array","items":{"type":"boolean"}},
"value_tested":{"type":"array","items":{"type":"number"}},"repeat_band":{"type":"number"},
"repeat_lower":{"type":"array","items":{"type":"number"}},
"repeat_upper":{"type":"array","items":{"type":"number"}}}}}}}"#;

#[cfg(test)]
mod tests {
    use super::*;
    use tyre_msgs::ModelCoefficient;

    fn state() -> ModelState {
        let (loads, slips, cambers, pressures) =
            (vec![2000.0, 4000.0, 6000.0], vec![-5.0, 0.0, 5.0], vec![-2.0, 0.0, 2.0], vec![1.8e5, 2.0e5, 2.2e5]);
        let n = loads.len() * slips.len() * cambers.len() * pressures.len();
        let (slips_n, cambers_n, pressures_n) = (slips.len(), cambers.len(), pressures.len());
        // value = the flat index, std = 1: the slice picks indices the test can recompute.
        let map = ModelMap {
            channel: "FYW".into(),
            slip_axis: "slip_angle_deg".into(),
            residual_rmse: 10.0,
            value: (0..n).map(|i| i as f64).collect(),
            std: vec![1.0; n],
        };
        // The largest slip angle lies outside the tested envelope.
        let maps_extrapolated = (0..n).map(|i| (i / (cambers_n * pressures_n)) % slips_n == slips_n - 1).collect();
        let stage = |name: &str, status: u8, coefficients: Vec<ModelCoefficient>| ModelStage {
            status,
            stage: name.into(),
            channel: "FY".into(),
            coefficients,
            ..ModelStage::default()
        };
        ModelState {
            update_index: 7,
            stages: vec![
                stage(
                    "fy_pure",
                    ModelStage::IDENTIFIED,
                    vec![
                        ModelCoefficient { key: "PDY1".into(), value: 1.2, std: 0.012 },
                        ModelCoefficient { key: "PKY1".into(), value: -20.0, std: 1.0 },
                        ModelCoefficient { key: "PEY1".into(), value: 0.0, std: 0.1 },
                    ],
                ),
                stage("mz_pure", ModelStage::WAITING, Vec::new()),
            ],
            grid_fz_n: loads,
            grid_slip_angle_deg: slips,
            grid_slip_ratio: vec![-0.1, 0.0, 0.1],
            grid_camber_deg: cambers,
            grid_pressure_pa: pressures,
            maps: vec![map],
            maps_extrapolated,
            maps_repeat_band: vec![2.5],
            ..ModelState::default()
        }
    }

    #[test]
    fn the_view_names_identified_stages_and_their_worst_coefficient() {
        let v = ModelView::of(&state());
        assert_eq!(v.identified, "1 / 2 stages identified");
        assert_eq!(v.stages[0].status, "identified");
        // PKY1: 1.0 / 20 = 5 % beats PDY1's 1 %; PEY1 at zero has no relative σ.
        assert!((v.stages[0].worst_relative_std_pct - 5.0).abs() < 1e-12);
        assert_eq!(v.stages[1].status, "waiting");
        assert!(v.stages[1].worst_relative_std_pct.is_nan());
    }

    #[test]
    fn the_band_is_the_slip_slice_at_the_middle_load_zero_camber_and_middle_pressure() {
        let v = ModelView::of(&state());
        let b = &v.bands[0];
        assert_eq!((b.fz_n, b.camber_deg, b.pressure_pa), (4000.0, 0.0, 2.0e5));
        // load 1 of 3, slip s, camber 1 of 3, pressure 1 of 3.
        let expect: Vec<f64> = (0..3).map(|s| (((3 + s) * 3 + 1) * 3 + 1) as f64).collect();
        assert_eq!(b.value, expect);
        assert_eq!(b.lower[0], expect[0] - 1.96);
        assert_eq!(b.upper[2], expect[2] + 1.96);
        assert_eq!(b.slip, vec![-5.0, 0.0, 5.0]);
        // The largest slip angle is extrapolated: flagged, and left out of the tested curve.
        assert_eq!(b.extrapolated, vec![false, false, true]);
        assert_eq!(&b.value_tested[..2], &expect[..2]);
        assert!(b.value_tested[2].is_nan());
    }

    #[test]
    fn the_band_for_a_repeat_measurement_is_drawn_around_the_curve() {
        let b = &ModelView::of(&state()).bands[0];
        assert_eq!(b.repeat_band, 2.5);
        for ((v, lo), hi) in b.value.iter().zip(&b.repeat_lower).zip(&b.repeat_upper) {
            assert_eq!((*lo, *hi), (v - 2.5, v + 2.5));
        }
        // A state recorded before the band existed draws none.
        let mut st = state();
        st.maps_repeat_band.clear();
        let b = &ModelView::of(&st).bands[0];
        assert!(b.repeat_band.is_nan() && b.repeat_upper.iter().all(|v| v.is_nan()));
    }

    #[test]
    fn a_map_without_the_extrapolated_flag_marks_nothing_extrapolated() {
        let mut st = state();
        st.maps_extrapolated.clear();
        let b = &ModelView::of(&st).bands[0];
        assert_eq!(b.extrapolated, vec![false; 3]);
        assert_eq!(b.value_tested, b.value);
    }

    #[test]
    fn a_map_of_the_wrong_size_is_skipped() {
        let mut st = state();
        st.maps[0].value.pop();
        assert!(ModelView::of(&st).bands.is_empty());
    }

    #[test]
    fn the_schema_names_every_field() {
        let schema: serde_json::Value = serde_json::from_str(MODEL_SCHEMA).expect("schema");
        let v = serde_json::to_value(ModelView::of(&state())).expect("json");
        for key in v.as_object().expect("object").keys() {
            assert!(schema["properties"].get(key).is_some(), "schema lacks {key}");
        }
        for key in v["bands"][0].as_object().expect("band").keys() {
            assert!(schema["properties"]["bands"]["items"]["properties"].get(key).is_some(), "schema lacks {key}");
        }
    }
}
