//! MCAP logs ⇄ [`Dataset`].
//!
//! Reading: the `tyre_msgs/msg/RigSample` topic (`/rig/sample`) is split into segments by the
//! `tyre_msgs/msg/ProcedureState` topic (`/rig/procedure/state`): a new segment starts whenever
//! the procedure, section, sweep name/index or phase changes. Only samples in
//! `PHASE_SWEEP` with a sweep name (data steps) and valid force channels are kept; the kind of
//! test comes from the sweep name (`OnCentre`, `RollingRadius`, `StepSteer`, `StaticDrag`,
//! `WarmUp`, `GraphSweep`, else a force & moment sweep).
//!
//! Writing: a dataset (e.g. imported from TYDEX or TTC files) becomes a log the fitter reads the
//! same way, with one `ProcedureState` per segment. What a `ProcedureState` cannot carry — the
//! kind, [`Cell`] and [`Origin`] of segments found in measured files — goes into a `segments`
//! metadata record (segment index → JSON) and comes back on reading.

use std::collections::BTreeMap;
use std::path::Path;

use mcaplog::{LogReader, McapLog, McapLogOptions};
use tyre_msgs::std_msgs::Header;
use tyre_msgs::{ProcedureState, RigSample, RigSetpoint, RosMessage};

use crate::data::{Cell, DataKind, Dataset, Origin, Procedure, Sample, Segment};
use crate::error::FitError;

fn log_err(path: &Path, message: impl ToString) -> FitError {
    FitError::Log { path: path.to_owned(), message: message.to_string() }
}

/// What the `segments` metadata record keeps of a segment found in a measured file.
#[derive(serde::Serialize, serde::Deserialize)]
struct SegmentMeta {
    kind: DataKind,
    cell: Option<Cell>,
    origin: Option<Origin>,
}

/// Metadata record name for [`SegmentMeta`] by segment index.
const SEGMENTS_RECORD: &str = "segments";

fn topic_of<M: RosMessage>(reader: &LogReader) -> Option<String> {
    let want = M::ros_type_name();
    reader.topics().into_iter().find(|t| t.ros_type == want).map(|t| t.topic)
}

/// Converts a rig sample (degrees, TYDEX names) to the fitter's sample (radians).
pub fn sample_of(s: &RigSample) -> Sample {
    Sample {
        time_s: s.runtime_s,
        fz_n: s.fzw_n,
        kappa: s.longslip,
        alpha_rad: s.slipangl_deg.to_radians(),
        gamma_rad: s.inclangl_deg.to_radians(),
        p_pa: s.inflpres_pa,
        vx_mps: s.trajvelw_mps,
        omega_radps: s.wheel_speed_radps,
        fx_n: s.fx_n,
        fy_n: s.fyw_n,
        mx_nm: s.mxw_nm,
        my_nm: s.myw_nm,
        mz_nm: s.mzw_nm,
        rl_m: s.dstwowhc_m,
        temp_c: s.trdtempc_c,
        temp_inner_c: s.trdtempi_c,
        temp_outer_c: s.trdtempo_c,
        road_temp_c: f64::NAN,
        dist_m: 0.0,
    }
}

/// Rebases time and integrates the travelled distance (LONGDISP) within a segment.
fn finish_segment(samples: &mut [Sample]) {
    if samples.is_empty() {
        return;
    }
    let t0 = samples[0].time_s;
    let mut d = 0.0;
    let mut prev: Option<(f64, f64)> = None;
    for s in samples.iter_mut() {
        if let Some((t, v)) = prev {
            d += 0.5 * (v + s.vx_mps) * (s.time_s - t);
        }
        prev = Some((s.time_s, s.vx_mps));
        s.time_s -= t0;
        s.dist_m = d;
    }
}

/// Cuts a stream of rig samples into the fitter's segments, each sample under the procedure
/// state that governs it: a new segment starts whenever the procedure, section, sweep name or
/// index, or phase changes; only `PHASE_SWEEP` samples of named steps with valid force channels
/// are kept. Reading a log and the live fit both use it, so both see the same segments.
#[derive(Debug, Default)]
pub struct Segmenter {
    /// The procedure when a state's name does not say it (a log's `procedure` metadata).
    pub md_procedure: Option<Procedure>,
    /// A log's `segments` metadata record (sweep index → JSON of kind, cell, origin).
    pub seg_meta: Option<BTreeMap<String, String>>,
    key: Option<(String, String, String, u32, u8)>,
    open: Option<Segment>,
}

impl Segmenter {
    /// Feeds one sample under its governing state; returns the segment this sample closed, if
    /// any (a closed segment with fewer than 3 samples is dropped).
    pub fn push(&mut self, st: &ProcedureState, s: &RigSample) -> Option<Segment> {
        let k = (st.procedure.clone(), st.section.clone(), st.sweep_name.clone(), st.sweep_index, st.phase);
        let mut closed = None;
        if self.key.as_ref() != Some(&k) {
            closed = self.finish();
            self.key = Some(k);
            if st.phase == ProcedureState::PHASE_SWEEP && !st.sweep_name.is_empty() {
                let procedure = Procedure::from_name(&st.procedure).or(self.md_procedure).unwrap_or(match s.rig_mode {
                    RigSetpoint::MODE_COUPLED => Procedure::BrkDrv,
                    RigSetpoint::MODE_STATIC => Procedure::StaticLong,
                    _ => Procedure::FreeRolling,
                });
                let meta: Option<SegmentMeta> = self
                    .seg_meta
                    .as_ref()
                    .and_then(|m| m.get(&st.sweep_index.to_string()))
                    .and_then(|j| serde_json::from_str(j).ok());
                self.open = Some(Segment {
                    procedure,
                    kind: meta
                        .as_ref()
                        .map(|m| m.kind)
                        .unwrap_or_else(|| DataKind::from_names(&st.section, &st.sweep_name)),
                    section: st.section.clone(),
                    sweep: st.sweep_name.clone(),
                    samples: Vec::new(),
                    cell: meta.as_ref().and_then(|m| m.cell),
                    origin: meta.and_then(|m| m.origin),
                });
            }
        }
        if let Some(seg) = self.open.as_mut()
            && s.fault_flags & RigSample::FAULT_FORCE == 0
        {
            seg.samples.push(sample_of(s));
        }
        closed
    }

    /// Closes the open segment (end of the stream, or a state change).
    pub fn finish(&mut self) -> Option<Segment> {
        let mut s = self.open.take()?;
        if s.samples.len() < 3 {
            return None;
        }
        finish_segment(&mut s.samples);
        Some(s)
    }

    /// True while a segment is open (a sweep is being recorded).
    pub fn in_segment(&self) -> bool {
        self.open.is_some()
    }
}

/// Reads one MCAP log into segments.
pub fn read_log(path: &Path) -> Result<Dataset, FitError> {
    read_log_with_warnings(path).map(|(d, _)| d)
}

/// As [`read_log`], with a warning per thing the log says it is missing (lost or malformed
/// messages, gaps in `RigSample.seq`); the fit report lists them.
pub fn read_log_with_warnings(path: &Path) -> Result<(Dataset, Vec<String>), FitError> {
    let reader = LogReader::open(path).map_err(|e| log_err(path, e))?;
    let loss = reader.loss_summary();
    let warnings = if loss.clean {
        Vec::new()
    } else {
        loss.lines.iter().map(|l| format!("data loss in {}: {}", path.display(), l.trim())).collect()
    };
    read_dataset(&reader, path).map(|d| (d, warnings))
}

fn read_dataset(reader: &LogReader, path: &Path) -> Result<Dataset, FitError> {
    let sample_topic =
        topic_of::<RigSample>(reader).ok_or_else(|| log_err(path, "no tyre_msgs/msg/RigSample topic"))?;
    let state_topic =
        topic_of::<ProcedureState>(reader).ok_or_else(|| log_err(path, "no tyre_msgs/msg/ProcedureState topic"))?;
    let samples = reader.typed::<RigSample>(&sample_topic).map_err(|e| log_err(path, e))?;
    let states = reader.typed::<ProcedureState>(&state_topic).map_err(|e| log_err(path, e))?;
    let md = reader.metadata();
    let fnomin = md
        .get("procedure")
        .and_then(|p| p.get("fz0_n"))
        .or_else(|| md.get("tyre").and_then(|t| t.get("fnomin_n")))
        .and_then(|v| v.parse::<f64>().ok());
    let md_procedure = md.get("procedure").and_then(|p| p.get("name")).and_then(|n| Procedure::from_name(n));
    let seg_meta = md.get(SEGMENTS_RECORD);

    let mut segmenter = Segmenter { md_procedure, seg_meta: seg_meta.cloned(), ..Segmenter::default() };
    let mut segments: Vec<Segment> = Vec::new();
    let mut si = 0usize;
    let mut current: Option<&ProcedureState> = None;
    for (t, s) in &samples {
        while si < states.len() && states[si].0 <= *t {
            current = Some(&states[si].1);
            si += 1;
        }
        let Some(st) = current else { continue };
        segments.extend(segmenter.push(st, s));
    }
    segments.extend(segmenter.finish());
    if segments.is_empty() {
        return Err(log_err(path, "no sweep data (no PHASE_SWEEP samples with a sweep name)"));
    }
    Ok(Dataset { segments, fnomin_n: fnomin, sources: vec![path.display().to_string()] })
}

/// Reads several logs (FreeRolling, BrkDrv, StaticLong) into one dataset.
pub fn read_logs(paths: &[&Path]) -> Result<Dataset, FitError> {
    let mut all = Dataset::default();
    for p in paths {
        all.extend(read_log(p)?);
    }
    Ok(all)
}

fn procedure_name(p: Procedure) -> &'static str {
    match p {
        Procedure::FreeRolling => "gs2mf_freerolling",
        Procedure::BrkDrv => "gs2mf_brkdrv",
        Procedure::StaticLong => "gs2mf_staticlong",
    }
}

/// The rig sample a fitter sample came from (inverse of [`sample_of`]); `t_s` is rig time.
pub fn rig_sample_of(s: &Sample, t_s: f64, seq: u64, procedure: Procedure) -> RigSample {
    RigSample {
        header: Header::iso_w(t_s),
        seq,
        runtime_s: t_s,
        fx_n: s.fx_n,
        fyw_n: s.fy_n,
        fzw_n: s.fz_n,
        mxw_nm: s.mx_nm,
        myw_nm: s.my_nm,
        mzw_nm: s.mz_nm,
        slipangl_deg: s.alpha_rad.to_degrees(),
        longslip: s.kappa,
        inclangl_deg: s.gamma_rad.to_degrees(),
        inflpres_pa: s.p_pa,
        trajvelw_mps: s.vx_mps,
        wheel_speed_radps: s.omega_radps,
        dstwowhc_m: s.rl_m,
        trdtempi_c: if s.temp_inner_c.is_finite() { s.temp_inner_c } else { s.temp_c },
        trdtempc_c: s.temp_c,
        trdtempo_c: if s.temp_outer_c.is_finite() { s.temp_outer_c } else { s.temp_c },
        rig_mode: match procedure {
            Procedure::FreeRolling => RigSetpoint::MODE_FREE_ROLLING,
            Procedure::BrkDrv => RigSetpoint::MODE_COUPLED,
            Procedure::StaticLong => RigSetpoint::MODE_STATIC,
        },
        fault_flags: 0,
    }
}

/// Writes a dataset as a ROS 2-profile MCAP log the fitter (and every MCAP tool) reads.
pub fn write_log(path: &Path, data: &Dataset) -> Result<(), FitError> {
    let werr = |e: mcaplog::LogWriteError| log_err(path, e);
    let mut log = McapLog::create(path, McapLogOptions::default()).map_err(werr)?;
    let mut meta = BTreeMap::new();
    meta.insert("software".to_owned(), "tyrerig import".to_owned());
    meta.insert("sources".to_owned(), data.sources.join(", "));
    log.write_metadata("tyrerig", &meta).map_err(werr)?;
    if let Some(f) = data.fnomin_n {
        let mut p = BTreeMap::new();
        p.insert("fz0_n".to_owned(), format!("{f}"));
        log.write_metadata("procedure", &p).map_err(werr)?;
    }
    let seg_meta: BTreeMap<String, String> = data
        .segments
        .iter()
        .enumerate()
        .filter(|(_, s)| s.cell.is_some() || s.origin.is_some())
        .filter_map(|(i, s)| {
            let m = SegmentMeta { kind: s.kind, cell: s.cell, origin: s.origin.clone() };
            serde_json::to_string(&m).ok().map(|j| (i.to_string(), j))
        })
        .collect();
    if !seg_meta.is_empty() {
        log.write_metadata(SEGMENTS_RECORD, &seg_meta).map_err(werr)?;
    }
    let schema = |t: &str| tyre_msgs::schema::ros2msg_schema_for(t).map_err(|e| log_err(path, e));
    let st_type = ProcedureState::ros_type_name();
    let rs_type = RigSample::ros_type_name();
    let ch_state = log.ensure_channel("/rig/procedure/state", &st_type, &schema(&st_type)?).map_err(werr)?;
    let ch_sample = log.ensure_channel("/rig/sample", &rs_type, &schema(&rs_type)?).map_err(werr)?;
    let enc = |e: tyre_msgs::cdr::CdrError| log_err(path, e);
    let mut t = 0.0_f64;
    let mut seq = 0u64;
    let ns = |t: f64| (t * 1e9).round() as u64;
    for (i, seg) in data.segments.iter().enumerate() {
        let mut st = ProcedureState {
            header: Header::iso_w(t),
            phase: ProcedureState::PHASE_SWEEP,
            procedure: procedure_name(seg.procedure).to_owned(),
            section: seg.section.clone(),
            section_index: 0,
            sweep_name: if seg.sweep.is_empty() { format!("segment_{i}") } else { seg.sweep.clone() },
            sweep_index: i as u32,
            sweep_count: data.segments.len() as u32,
            ..ProcedureState::default()
        };
        log.write(ch_state, ns(t), ns(t), &tyre_msgs::cdr::to_cdr_with_header(&st).map_err(enc)?).map_err(werr)?;
        // The run's own clock where it runs forward (an imported file's elapsed time), so the
        // time between sweeps (cooling, wear) survives; otherwise just after the last record.
        let s0 = seg.samples.first().map(|s| s.time_s).unwrap_or(0.0);
        let t_seg = if s0.is_finite() && s0 > t + 1e-3 { s0 } else { t + 1e-3 };
        for s in &seg.samples {
            let ts = t_seg + (s.time_s - s0);
            let rs = rig_sample_of(s, ts, seq, seg.procedure);
            seq += 1;
            log.write(ch_sample, ns(ts), ns(ts), &tyre_msgs::cdr::to_cdr_with_header(&rs).map_err(enc)?)
                .map_err(werr)?;
            t = ts;
        }
        t += 0.5;
        st.phase = ProcedureState::PHASE_SETTLE;
        st.header = Header::iso_w(t);
        log.write(ch_state, ns(t), ns(t), &tyre_msgs::cdr::to_cdr_with_header(&st).map_err(enc)?).map_err(werr)?;
        t += 0.5;
    }
    log.finish().map_err(werr)?;
    Ok(())
}
