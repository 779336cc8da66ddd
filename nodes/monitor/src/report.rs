//! The end-of-run report (`tyrerig report <log.mcap> --out <dir>`): replays the log's samples and
//! procedure states through the channels and monitor cores ([`crate::Pipeline`]) and writes
//! `report.md` with the thesis's plots (PNG and/or SVG), the derived measurements and every
//! alarm.
//!
//! Plots (thesis §3.6, §3.9, §5.1.2):
//! - `graph_sweeps_<procedure>`: graph sweep 1 vs 2 overlays, FYW–SLIPANGL (FreeRolling) or
//!   FX–LONGSLIP (BrkDrv), one panel per sweep of the block;
//! - `dstwowhc_<procedure>`: DSTWOWHC vs zeroed runtime of the same sweeps (the wear between
//!   the blocks shows as an offset);
//! - `trdtempc`: TRDTEMPC vs runtime with the 45 °C baseline;
//! - `temp_vs_energy`: peak TRDTEMPC vs sliding energy per sweep, with the thesis's power law
//!   y = 40.41·x^0.1264 (x in kJ);
//! - `wear`: the monitor's wear estimate vs runtime, with the usable tread.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use channels::{ChannelsConfig, DerivedMeasurement, Quantity};
use mcaplog::{LogReader, codec};
use plotters::coord::Shift;
use plotters::prelude::*;
use tyre_msgs::{
    ModelStage, ModelState, ProcedureState, QualityCheck, QualityReport, RigSample, RosMessage, SweepSummary,
};

use crate::config::{MonitorConfig, TyreInfo};
use crate::core::{Alarm, DriftRecord, WearEstimate};
use crate::model_watch::ModelWatch;
use crate::pipeline::{Pipeline, PipelineError, PipelineOutput};

/// Why a report could not be made. Names the file or topic.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The log could not be read.
    #[error(transparent)]
    Log(#[from] mcaplog::LogError),
    /// A message did not decode.
    #[error("{path}: message {index} on {topic} does not decode as {ros_type}: {detail}")]
    Decode {
        /// The log.
        path: PathBuf,
        /// Topic.
        topic: String,
        /// Its type.
        ros_type: String,
        /// Index in the log.
        index: usize,
        /// Decoder's words.
        detail: String,
    },
    /// The log has no `tyre_msgs/msg/RigSample` messages.
    #[error("{0}: no tyre_msgs/msg/RigSample messages to replay")]
    NoSamples(PathBuf),
    /// The tyre's rating is neither given nor in the log's metadata.
    #[error("{path}: no tyre rating: pass --load-index, or log metadata `tyre.fnomin_n` / `tyre.load_index`")]
    NoTyre {
        /// The log.
        path: PathBuf,
    },
    /// The cores refused their configuration.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// Writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// Drawing a plot failed.
    #[error("{path}: drawing failed: {detail}")]
    Plot {
        /// The image.
        path: PathBuf,
        /// What failed.
        detail: String,
    },
}

/// One input of a replay, in log order.
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// A `tyre_msgs/RigSample`.
    Sample(RigSample),
    /// A `tyre_msgs/ProcedureState`.
    State(ProcedureState),
}

/// The replay's inputs from a log: samples and procedure states, selected by type (whatever the
/// namespace), in log order.
pub fn inputs(reader: &LogReader) -> Result<Vec<Input>, ReportError> {
    let mut out = Vec::new();
    let (sample_t, state_t) = (RigSample::ros_type_name(), ProcedureState::ros_type_name());
    for (index, m) in reader.messages().iter().enumerate() {
        let err = |detail: String| ReportError::Decode {
            path: reader.path().to_owned(),
            topic: m.topic.clone(),
            ros_type: m.ros_type.clone(),
            index,
            detail,
        };
        if m.ros_type == sample_t {
            out.push(Input::Sample(codec::decode(&m.data, &m.ros_type).map_err(|e| err(e.to_string()))?));
        } else if m.ros_type == state_t {
            out.push(Input::State(codec::decode(&m.data, &m.ros_type).map_err(|e| err(e.to_string()))?));
        }
    }
    if !out.iter().any(|i| matches!(i, Input::Sample(_))) {
        return Err(ReportError::NoSamples(reader.path().to_owned()));
    }
    Ok(out)
}

/// The live fit's model states in the log (`tyre_msgs/ModelState`, whatever the namespace), in
/// log order; empty when the run had no live fit.
pub fn model_states(reader: &LogReader) -> Result<Vec<ModelState>, ReportError> {
    let ty = ModelState::ros_type_name();
    let mut out = Vec::new();
    for (index, m) in reader.messages().iter().enumerate().filter(|(_, m)| m.ros_type == ty) {
        out.push(codec::decode(&m.data, &m.ros_type).map_err(|e| ReportError::Decode {
            path: reader.path().to_owned(),
            topic: m.topic.clone(),
            ros_type: m.ros_type.clone(),
            index,
            detail: e.to_string(),
        })?);
    }
    Ok(out)
}

/// The tyre as the log's metadata describes it: the declared rating from the tyre file's
/// `fnomin_n` (the smallest load index whose Fz0 reaches it), the entered one from
/// `tyre.load_index` (the index the procedure's loads were built from).
pub fn tyre_from_metadata(reader: &LogReader) -> Option<TyreInfo> {
    let md = reader.metadata();
    let tyre = md.get("tyre")?;
    let entered: Option<u32> = tyre.get("load_index").and_then(|v| v.parse().ok());
    let declared = tyre
        .get("declared_load_index")
        .and_then(|v| v.parse().ok())
        .or_else(|| {
            let fnomin: f64 = tyre.get("fnomin_n")?.parse().ok()?;
            (60..=130).find(|&li| procedure::fz0_n(li).is_ok_and(|f| f >= 0.99 * fnomin))
        })
        .or(entered)?;
    let mut t = TyreInfo::from_load_index(declared).ok()?;
    t.entered_load_index = entered;
    Some(t)
}

/// A graph sweep's trace for the overlays.
#[derive(Debug, Clone, Default)]
pub struct GraphTrace {
    /// Procedure.
    pub procedure: String,
    /// Block (0 = graph sweep 1, 1 = graph sweep 2).
    pub block: usize,
    /// Position in the block.
    pub ordinal: usize,
    /// Sweep name.
    pub name: String,
    /// (slip angle deg, slip ratio, FYW, FX, DSTWOWHC, zeroed runtime).
    pub pts: Vec<[f64; 6]>,
}

impl GraphTrace {
    fn longitudinal(&self) -> bool {
        let (lo, hi) = self.pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p[1]), h.max(p[1])));
        hi - lo > 0.02
    }
}

/// What a replay found.
#[derive(Debug, Clone, Default)]
pub struct Replay {
    /// Sweep summaries with their final cool-down.
    pub summaries: Vec<SweepSummary>,
    /// Derived measurements.
    pub derived: Vec<DerivedMeasurement>,
    /// Alarms, in order.
    pub alarms: Vec<Alarm>,
    /// The monitor's last report.
    pub final_report: QualityReport,
    /// Wear of the specimen on the rig at the end.
    pub wear: Option<WearEstimate>,
    /// Wear per specimen [mm].
    pub wear_by_specimen_mm: Vec<f64>,
    /// Graph-sweep comparisons.
    pub drifts: Vec<DriftRecord>,
    /// Largest sustained load / declared Fz0.
    pub max_load_factor: f64,
    /// (RUNTIME, TRDTEMPC), every 10th sample.
    pub temp_trace: Vec<(f64, f64)>,
    /// (RUNTIME, wear mm) from each report.
    pub wear_trace: Vec<(f64, f64)>,
    /// Graph sweeps.
    pub graph: Vec<GraphTrace>,
    /// The tyre judged.
    pub tyre: Option<TyreInfo>,
    /// Samples replayed.
    pub samples: usize,
    /// Last RUNTIME [s].
    pub end_time_s: f64,
    /// What the log is missing (`LogReader::loss_summary`), filled by [`run`].
    pub data_loss: Vec<String>,
    /// The live fit's progress, when the log has `model/state` (filled by [`run`]).
    pub model: Option<ModelWatch>,
}

/// Replays `inputs` through a fresh pipeline, handing every output to `each` (a test compares
/// them with the live ones) and collecting what the report needs.
pub fn replay(
    inputs: &[Input],
    channels_cfg: ChannelsConfig,
    monitor_cfg: MonitorConfig,
    tyre: TyreInfo,
    each: &mut dyn FnMut(&PipelineOutput),
) -> Result<Replay, ReportError> {
    let mut p = Pipeline::new(channels_cfg, monitor_cfg, tyre.clone())?;
    let mut r = Replay { tyre: Some(tyre), ..Replay::default() };
    let mut state = ProcedureState::default();
    // Graph-sweep blocks: (procedure) → section indices seen.
    let mut blocks: BTreeMap<String, Vec<u32>> = BTreeMap::new();
    let mut counts: BTreeMap<(String, usize), usize> = BTreeMap::new();
    let mut current: Option<GraphTrace> = None;
    let mut current_key: Option<(u32, String)> = None;
    let mut t0 = f64::NAN;
    let collect = |r: &mut Replay, o: &PipelineOutput| {
        r.summaries.extend(o.sweep_summaries.iter().filter(|s| s.cool_down_complete).cloned());
        r.derived.extend(o.derived.iter().cloned());
        r.alarms.extend(o.alarms.iter().cloned());
        if let Some(rep) = &o.report {
            if rep.wear_mm.is_finite() {
                r.wear_trace.push((rep.header.stamp.as_secs_f64(), rep.wear_mm));
            }
            r.final_report = rep.clone();
        }
    };
    for input in inputs {
        match input {
            Input::State(st) => {
                p.on_procedure_state(st);
                let key = (st.sweep_index, st.sweep_name.clone());
                let graph = st.phase == ProcedureState::PHASE_SWEEP && st.sweep_name.contains("GraphSweep");
                if current.is_some() && (!graph || current_key.as_ref() != Some(&key)) {
                    r.graph.extend(current.take());
                    current_key = None;
                }
                if graph && current.is_none() {
                    let secs = blocks.entry(st.procedure.clone()).or_default();
                    let block = secs.iter().position(|s| *s == st.section_index).unwrap_or_else(|| {
                        secs.push(st.section_index);
                        secs.len() - 1
                    });
                    let c = counts.entry((st.procedure.clone(), block)).or_default();
                    current = Some(GraphTrace {
                        procedure: st.procedure.clone(),
                        block,
                        ordinal: *c,
                        name: st.sweep_name.clone(),
                        pts: Vec::new(),
                    });
                    *c += 1;
                    current_key = Some(key);
                    t0 = f64::NAN;
                }
                state = st.clone();
            }
            Input::Sample(s) => {
                let o = p.on_sample(s);
                each(&o);
                collect(&mut r, &o);
                if r.samples.is_multiple_of(10) && s.trdtempc_c.is_finite() {
                    r.temp_trace.push((s.runtime_s, s.trdtempc_c));
                }
                r.samples += 1;
                r.end_time_s = s.runtime_s;
                if let Some(g) = current.as_mut()
                    && state.phase == ProcedureState::PHASE_SWEEP
                {
                    if t0.is_nan() {
                        t0 = s.runtime_s;
                    }
                    g.pts.push([s.slipangl_deg, s.longslip, s.fyw_n, s.fx_n, s.dstwowhc_m, s.runtime_s - t0]);
                }
            }
        }
    }
    r.graph.extend(current.take());
    let o = p.finish();
    each(&o);
    collect(&mut r, &o);
    r.wear = Some(p.monitor.wear());
    r.wear_by_specimen_mm = p.monitor.wear_by_specimen_mm();
    r.drifts = p.monitor.drifts().to_vec();
    r.max_load_factor = p.monitor.max_load_factor();
    r.final_report = p.monitor.report(r.end_time_s);
    Ok(r)
}

/// Image formats to write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// PNG only.
    Png,
    /// SVG only.
    Svg,
    /// Both.
    Both,
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(120, 60, 160),
];

#[derive(Debug, Clone)]
struct Series {
    label: String,
    points: Vec<(f64, f64)>,
    color: usize,
    dots: bool,
}

#[derive(Debug, Clone)]
struct Panel {
    /// Where the legend sits (where the curves leave room).
    legend: SeriesLabelPosition,
    title: String,
    x_label: String,
    y_label: String,
    series: Vec<Series>,
}

fn bounds(p: &Panel) -> (f64, f64, f64, f64) {
    let mut b = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in p.series.iter().flat_map(|s| s.points.iter()).filter(|(x, y)| x.is_finite() && y.is_finite()) {
        b = (b.0.min(*x), b.1.max(*x), b.2.min(*y), b.3.max(*y));
    }
    if b.0 > b.1 {
        return (0.0, 1.0, 0.0, 1.0);
    }
    let pad = |lo: f64, hi: f64| {
        let span = (hi - lo).abs().max(1e-9);
        (lo - 0.05 * span, hi + 0.05 * span)
    };
    let (x0, x1) = pad(b.0, b.1);
    let (y0, y1) = pad(b.2, b.3);
    (x0, x1, y0, y1)
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let (x0, x1, y0, y1) = bounds(p);
    let mut ctx = ChartBuilder::on(area)
        .caption(&p.title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    let ydec = if (y1 - y0).abs() < 0.05 {
        4
    } else if (y1 - y0).abs() < 5.0 {
        2
    } else {
        0
    };
    ctx.configure_mesh()
        .y_label_formatter(&|v| format!("{v:.ydec$}"))
        .x_desc(p.x_label.as_str())
        .y_desc(p.y_label.as_str())
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    for s in &p.series {
        let color = PALETTE[s.color % PALETTE.len()];
        let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(|(x, y)| x.is_finite() && y.is_finite()).collect();
        let legend =
            move |(x, y): (i32, i32)| PathElement::new([(x, y), (x + 18, y)], ShapeStyle::from(&color).stroke_width(2));
        if s.dots {
            let drawn = ctx
                .draw_series(pts.iter().map(|&(x, y)| Circle::new((x, y), 3, ShapeStyle::from(&color).filled())))
                .map_err(err)?;
            if !s.label.is_empty() {
                drawn.label(s.label.clone()).legend(legend);
            }
        } else {
            let drawn = ctx.draw_series(LineSeries::new(pts, ShapeStyle::from(&color).stroke_width(2))).map_err(err)?;
            if !s.label.is_empty() {
                drawn.label(s.label.clone()).legend(legend);
            }
        }
    }
    if p.series.iter().any(|s| !s.label.is_empty()) {
        ctx.configure_series_labels()
            .position(p.legend.clone())
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .label_font(("sans-serif", 13))
            .draw()
            .map_err(err)?;
    }
    Ok(())
}

/// Draws `panels` in a grid of `cols` columns into `<dir>/<stem>.png|svg`; returns the files.
fn draw(dir: &Path, stem: &str, panels: &[Panel], cols: usize, format: Format) -> Result<Vec<PathBuf>, ReportError> {
    let cols = cols.max(1).min(panels.len().max(1));
    let rows = panels.len().div_ceil(cols).max(1);
    let size = ((560 * cols) as u32, (420 * rows) as u32);
    let mut written = Vec::new();
    let mut one = |path: PathBuf, svg: bool| -> Result<(), ReportError> {
        let res = if svg {
            let root = SVGBackend::new(&path, size).into_drawing_area();
            render(&root, panels, rows, cols)
        } else {
            let root = BitMapBackend::new(&path, size).into_drawing_area();
            render(&root, panels, rows, cols)
        };
        res.map_err(|detail| ReportError::Plot { path: path.clone(), detail })?;
        written.push(path);
        Ok(())
    };
    if matches!(format, Format::Png | Format::Both) {
        one(dir.join(format!("{stem}.png")), false)?;
    }
    if matches!(format, Format::Svg | Format::Both) {
        one(dir.join(format!("{stem}.svg")), true)?;
    }
    Ok(written)
}

fn render<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panels: &[Panel],
    rows: usize,
    cols: usize,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let areas = root.split_evenly((rows, cols));
    for (a, p) in areas.iter().zip(panels) {
        draw_panel(a, p)?;
    }
    root.present().map_err(|e| e.to_string())
}

/// The thesis's fit of peak sweep temperature against sliding energy (§3.6.2): y = 40.41·x^0.1264,
/// x in kJ, R² = 0.9887.
pub fn thesis_peak_temp_c(energy_kj: f64) -> f64 {
    40.41 * energy_kj.powf(0.1264)
}

/// Writes `report.md` and its plots into `out_dir`; returns the report's path.
pub fn write_report(r: &Replay, log_name: &str, out_dir: &Path, format: Format) -> Result<PathBuf, ReportError> {
    std::fs::create_dir_all(out_dir).map_err(|source| ReportError::Io { path: out_dir.to_owned(), source })?;
    let mut figs: Vec<(String, String)> = Vec::new(); // (caption, file name)
    let ext = if format == Format::Svg { "svg" } else { "png" };
    let mut add = |caption: String, stem: String, files: Vec<PathBuf>| {
        if !files.is_empty() {
            figs.push((caption, format!("{stem}.{ext}")));
        }
    };
    // Graph sweep overlays, per procedure.
    let procedures: Vec<String> = {
        let mut v: Vec<String> = r.graph.iter().map(|g| g.procedure.clone()).collect();
        v.dedup();
        v
    };
    for proc_ in &procedures {
        let traces: Vec<&GraphTrace> = r.graph.iter().filter(|g| &g.procedure == proc_).collect();
        let n = traces.iter().map(|g| g.ordinal + 1).max().unwrap_or(0);
        let mut force_panels = Vec::new();
        let mut radius_panels = Vec::new();
        for ord in 0..n {
            let pair: Vec<&&GraphTrace> = traces.iter().filter(|g| g.ordinal == ord).collect();
            let long = pair.first().is_some_and(|g| g.longitudinal());
            let mut fs = Vec::new();
            let mut rs = Vec::new();
            for g in &pair {
                let label = format!("graph sweep {}", g.block + 1);
                let pts = g.pts.iter().map(|p| if long { (p[1], p[3]) } else { (p[0], p[2]) }).collect();
                fs.push(Series { label: label.clone(), points: pts, color: g.block, dots: false });
                rs.push(Series {
                    label,
                    points: g.pts.iter().map(|p| (p[5], p[4])).collect(),
                    color: g.block,
                    dots: false,
                });
            }
            let title = format!("graph sweep #{}", ord + 1);
            force_panels.push(Panel {
                // FX rises to the upper right; FYW (ISO-W) falls to the lower right.
                legend: if long { SeriesLabelPosition::LowerRight } else { SeriesLabelPosition::UpperRight },
                title: title.clone(),
                x_label: if long { "LONGSLIP [-]" } else { "SLIPANGL [deg]" }.into(),
                y_label: if long { "FX [N]" } else { "FYW [N]" }.into(),
                series: fs,
            });
            radius_panels.push(Panel {
                legend: SeriesLabelPosition::UpperRight,
                title,
                x_label: "zeroed RUNTIME [s]".into(),
                y_label: "DSTWOWHC [m]".into(),
                series: rs,
            });
        }
        if !force_panels.is_empty() {
            let stem = format!("graph_sweeps_{proc_}");
            let files = draw(out_dir, &stem, &force_panels, 3, format)?;
            add(format!("Graph sweep 1 vs 2, {proc_} (thesis §3.9)"), stem, files);
            let stem = format!("dstwowhc_{proc_}");
            let files = draw(out_dir, &stem, &radius_panels, 3, format)?;
            add(
                format!("DSTWOWHC vs zeroed runtime, graph sweeps 1 and 2, {proc_} (wear shows as an offset)"),
                stem,
                files,
            );
        }
    }
    // Temperature vs runtime with the baseline.
    if !r.temp_trace.is_empty() {
        let (t0, t1) = (r.temp_trace[0].0, r.temp_trace[r.temp_trace.len() - 1].0);
        let p = Panel {
            legend: SeriesLabelPosition::UpperRight,
            title: "TRDTEMPC vs runtime".into(),
            x_label: "RUNTIME [s]".into(),
            y_label: "TRDTEMPC [°C]".into(),
            series: vec![
                Series { label: "TRDTEMPC".into(), points: r.temp_trace.clone(), color: 0, dots: false },
                Series { label: "baseline 45 °C".into(), points: vec![(t0, 45.0), (t1, 45.0)], color: 1, dots: false },
            ],
        };
        let files = draw(out_dir, "trdtempc", &[p], 1, format)?;
        add("TRDTEMPC vs runtime with the 45 °C baseline (thesis §3.5)".into(), "trdtempc".into(), files);
    }
    // Peak temperature vs sliding energy.
    let sweeps: Vec<(f64, f64)> = r
        .summaries
        .iter()
        .filter(|s| s.sliding_energy_j > 1e3 && s.peak_temp_c.is_finite())
        .map(|s| (s.sliding_energy_j / 1e3, s.peak_temp_c))
        .collect();
    if !sweeps.is_empty() {
        let emax = sweeps.iter().map(|p| p.0).fold(1.0, f64::max);
        let law: Vec<(f64, f64)> =
            (1..=100).map(|i| emax * f64::from(i) / 100.0).map(|e| (e, thesis_peak_temp_c(e))).collect();
        let p = Panel {
            legend: SeriesLabelPosition::LowerRight,
            title: "Peak TRDTEMPC vs sliding energy per sweep".into(),
            x_label: "sliding energy [kJ]".into(),
            y_label: "peak TRDTEMPC [°C]".into(),
            series: vec![
                Series { label: "sweeps".into(), points: sweeps, color: 0, dots: true },
                Series { label: "thesis 40.41·x^0.1264".into(), points: law, color: 1, dots: false },
            ],
        };
        let files = draw(out_dir, "temp_vs_energy", &[p], 1, format)?;
        add(
            "Peak sweep temperature vs sliding energy (thesis §3.6.2 power law)".into(),
            "temp_vs_energy".into(),
            files,
        );
    }
    if !r.wear_trace.is_empty() {
        let usable = r.tyre.as_ref().map_or(4.0, TyreInfo::usable_mm);
        let (t0, t1) = (r.wear_trace[0].0, r.wear_trace[r.wear_trace.len() - 1].0);
        let p = Panel {
            legend: SeriesLabelPosition::UpperLeft,
            title: "Tread wear from DSTWOWHC (monitor)".into(),
            x_label: "RUNTIME [s]".into(),
            y_label: "wear [mm]".into(),
            series: vec![
                Series { label: "measured".into(), points: r.wear_trace.clone(), color: 0, dots: true },
                Series {
                    label: "50 % usable".into(),
                    points: vec![(t0, usable / 2.0), (t1, usable / 2.0)],
                    color: 1,
                    dots: false,
                },
            ],
        };
        let files = draw(out_dir, "wear", &[p], 1, format)?;
        add(
            "Wear estimate vs runtime (zero-slip holds, averaged below the 0.1 mm resolution)".into(),
            "wear".into(),
            files,
        );
    }

    // The live fit: each stage's error after every update.
    if let Some(w) = r.model.as_ref().filter(|w| w.stages().any(|h| !h.nrmse_trace.is_empty())) {
        let series = w
            .stages()
            .filter(|h| !h.nrmse_trace.is_empty())
            .enumerate()
            .map(|(i, h)| Series {
                label: h.stage.clone(),
                points: h.nrmse_trace.clone(),
                color: i,
                // Past the palette the markers tell the stages apart.
                dots: i >= PALETTE.len(),
            })
            .collect();
        let p = Panel {
            legend: SeriesLabelPosition::UpperRight,
            title: "Live fit: stage NRMSE after each update".into(),
            x_label: "rig time [s]".into(),
            y_label: "NRMSE [% of peak]".into(),
            series,
        };
        let files = draw(out_dir, "live_model", &[p], 1, format)?;
        add(
            "Live fit: each stage's RMS residual (% of its peak) after every update".into(),
            "live_model".into(),
            files,
        );
    }

    let md = markdown(r, log_name, &figs);
    let path = out_dir.join("report.md");
    std::fs::write(&path, md).map_err(|source| ReportError::Io { path: path.clone(), source })?;
    Ok(path)
}

fn level_name(l: u8) -> &'static str {
    match l {
        QualityCheck::OK => "OK",
        QualityCheck::WARN => "WARN",
        _ => "ERROR",
    }
}

fn fmt(v: f64, dec: usize) -> String {
    if v.is_finite() { format!("{v:.dec$}") } else { "–".into() }
}

fn markdown(r: &Replay, log_name: &str, figs: &[(String, String)]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# tyrerig run report: `{log_name}`\n");
    if let Some(t) = &r.tyre {
        let _ = writeln!(
            s,
            "Tyre: declared load index {} (Fz0 {:.0} N){}; tread {:.1} mm new, {:.1} mm legal minimum.  ",
            t.load_index,
            t.fz0_n,
            t.entered_load_index.map_or(String::new(), |e| format!(", index entered at the rig {e}")),
            t.tread_new_mm,
            t.tread_min_mm
        );
    }
    let _ = writeln!(s, "{} samples replayed, rig time {:.0} s.\n", r.samples, r.end_time_s);
    let rep = &r.final_report;
    let _ = writeln!(s, "## Verdict: {}\n", level_name(rep.level));
    let _ = writeln!(s, "| check | level | message |\n|---|---|---|");
    for c in &rep.checks {
        let _ = writeln!(s, "| {} | {} | {} |", c.check, level_name(c.level), c.message.replace('|', "\\|"));
    }
    let _ = writeln!(s, "\n## Alarms\n");
    if r.alarms.is_empty() {
        let _ = writeln!(s, "None.");
    } else {
        let _ = writeln!(s, "| rig time s | level | check | message |\n|---|---|---|---|");
        for a in &r.alarms {
            let _ =
                writeln!(s, "| {:.1} | {} | {} | {} |", a.rig_time_s, a.level, a.check, a.message.replace('|', "\\|"));
        }
    }
    if let Some(w) = &r.model {
        live_model_markdown(&mut s, w);
    }
    if !r.data_loss.is_empty() {
        let _ = writeln!(s, "\n## Data loss\n");
        for l in &r.data_loss {
            let _ = writeln!(s, "- {}", l.trim());
        }
    }
    let _ = writeln!(s, "\n## Wear\n");
    if let Some(w) = &r.wear {
        let _ = writeln!(
            s,
            "Measured {} ± {} mm (2σ) from DSTWOWHC at matched zero-slip holds; forecast at the end {} mm. Per \
             specimen: {}.\n",
            fmt(w.wear_mm, 2),
            fmt(w.wear_2sigma_mm, 2),
            fmt(w.forecast_mm, 2),
            r.wear_by_specimen_mm.iter().map(|v| format!("{} mm", fmt(*v, 2))).collect::<Vec<_>>().join(", ")
        );
    }
    let _ = writeln!(s, "Largest sustained load: {:.2} × the declared Fz0.\n", r.max_load_factor);
    if !r.drifts.is_empty() {
        let _ = writeln!(s, "## Graph-sweep drift (graph sweep 2 vs 1)\n");
        let _ = writeln!(
            s,
            "| procedure | # | level | curve RMS % | peak % | peak shift | stiffness % | temperature % |\n|---|---|---|---|---|---|---|---|"
        );
        for d in &r.drifts {
            let x = &d.drift;
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} {} | {} | {} |",
                d.procedure,
                d.ordinal + 1,
                level_name(d.level),
                fmt(x.rms_pct, 1),
                fmt(x.peak_pct, 1),
                fmt(x.peak_shift, 2),
                if x.longitudinal { "% SR" } else { "°" },
                fmt(x.stiffness_pct, 1),
                fmt(x.temp_pct, 1)
            );
        }
    }
    let _ = writeln!(s, "\n## Derived measurements\n");
    let order = [
        Quantity::CorneringStiffness,
        Quantity::Rsat,
        Quantity::Rcf,
        Quantity::VerticalStiffness,
        Quantity::UnloadedRadius,
        Quantity::LateralRelaxationLength,
        Quantity::LongitudinalStiffness,
        Quantity::LoadedRadius,
    ];
    for q in order {
        let ms: Vec<&DerivedMeasurement> = r.derived.iter().filter(|m| m.quantity == q).collect();
        if ms.is_empty() {
            continue;
        }
        let _ = writeln!(s, "### {} [{}]\n", q.name(), q.unit());
        let _ = writeln!(
            s,
            "| section | value | Fz N | pressure bar | speed m/s | SA deg | n |\n|---|---|---|---|---|---|---|"
        );
        for m in ms {
            let dec = match q {
                Quantity::LoadedRadius | Quantity::UnloadedRadius | Quantity::LateralRelaxationLength => 4,
                Quantity::Rsat | Quantity::Rcf => 1,
                _ => 0,
            };
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} |",
                m.section,
                fmt(m.value, dec),
                fmt(m.fz_n, 0),
                fmt(m.pressure_pa / 1e5, 2),
                fmt(m.speed_mps, 1),
                fmt(m.slip_angle_deg, 2),
                m.n_points
            );
        }
        let _ = writeln!(s);
    }
    if !figs.is_empty() {
        let _ = writeln!(s, "## Plots\n");
        for (caption, file) in figs {
            let _ = writeln!(s, "### {caption}\n\n![{caption}]({file})\n");
        }
    }
    let _ = writeln!(s, "## Sweeps\n");
    let _ = writeln!(
        s,
        "| # | sweep | start s | duration s | start °C | peak °C | energy kJ | cool-down s | hysteresis N | mean Fz N | hot |\n|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for x in &r.summaries {
        let _ = writeln!(
            s,
            "| {} | {} | {:.1} | {:.1} | {} | {} | {:.1} | {:.1} | {} | {:.0} | {} |",
            x.sweep_index,
            x.sweep_name,
            x.start_time_s,
            x.duration_s,
            fmt(x.start_temp_c, 1),
            fmt(x.peak_temp_c, 1),
            x.sliding_energy_j / 1e3,
            x.cool_down_s,
            fmt(x.mech_hysteresis_n, 0),
            x.mean_fz_n,
            if x.started_hot { "yes" } else { "" }
        );
    }
    s
}

/// The live fit's section: per stage when it became identified and where it ended.
fn live_model_markdown(s: &mut String, w: &ModelWatch) {
    let (n_id, n) = w.identified();
    let _ = writeln!(s, "\n## Live model\n");
    let _ = writeln!(
        s,
        "{} updates ({} failed; the first ones may wait for data){}; {n_id} of {n} stages identified at the end.\n",
        w.updates(),
        w.failed_updates(),
        if w.final_seen() { ", the final one at the procedure's end" } else { "; no final update in the log" }
    );
    let _ = writeln!(
        s,
        "| stage | channel | status | identified at rig s | NRMSE % | points | worst σ/value | lost identification | why not identified |\n|---|---|---|---|---|---|---|---|---|"
    );
    for h in w.stages() {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            h.stage,
            h.channel,
            ModelStage::status_name(h.status),
            h.first_identified_s.map_or("–".into(), |t| format!("{t:.0}")),
            h.nrmse_trace.last().map_or("–".into(), |(_, v)| fmt(*v, 2)),
            h.points,
            match (h.worst_rel_std, h.worst_key.as_str()) {
                (_, "") => "–".to_owned(),
                (r, k) if r.is_infinite() => format!("∞ ({k})"),
                (r, k) => format!("{} ({k})", fmt(r, 3)),
            },
            h.lost_identification,
            h.reason.replace('|', "\\|")
        );
    }
    let warnings: Vec<_> = w.events().iter().filter(|e| e.level != QualityCheck::OK).collect();
    if !warnings.is_empty() {
        let _ = writeln!(s, "\n| rig time s | warning |\n|---|---|");
        for e in warnings {
            let _ = writeln!(s, "| {:.1} | {} |", e.rig_time_s, e.message.replace('|', "\\|"));
        }
    }
}

/// Reads `log`, replays it and writes the report into `out_dir`. `tyre` overrides the log's
/// metadata.
pub fn run(
    log: &Path,
    out_dir: &Path,
    tyre: Option<TyreInfo>,
    channels_cfg: ChannelsConfig,
    monitor_cfg: MonitorConfig,
    format: Format,
) -> Result<(PathBuf, Replay), ReportError> {
    let reader = LogReader::open(log)?;
    let tyre =
        tyre.or_else(|| tyre_from_metadata(&reader)).ok_or_else(|| ReportError::NoTyre { path: log.to_owned() })?;
    let ins = inputs(&reader)?;
    let mut r = replay(&ins, channels_cfg, monitor_cfg, tyre, &mut |_| {})?;
    r.data_loss = reader.loss_summary().lines;
    let models = model_states(&reader)?;
    if !models.is_empty() {
        let mut w = ModelWatch::new();
        for m in &models {
            w.on_model_state(m);
        }
        r.model = Some(w);
    }
    let name = log.file_name().map_or_else(|| log.display().to_string(), |n| n.to_string_lossy().into_owned());
    let path = write_report(&r, &name, out_dir, format)?;
    Ok((path, r))
}
