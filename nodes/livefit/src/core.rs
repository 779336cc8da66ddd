//! The live fit's pure core: samples and procedure states in, an update due after every
//! completed data segment, a [`ModelState`] per update.

use std::collections::VecDeque;
use std::sync::Arc;

use adaptive::ModelSnapshot;
use mffit::logs::Segmenter;
use mffit::prediction::{EnvelopeGrid, PredictionMap, prediction_maps_since};
use mffit::stages::UPSTREAM_NOTE;
use mffit::{DataKind, Dataset, FitResult, Segment, WarmStart};
use tyre_msgs::builtin_interfaces::Time;
use tyre_msgs::{ModelCovariance, ModelState, ProcedureState, RigSample};

use crate::config::LiveFitConfig;
use crate::state::model_state;

/// What a message made due.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Trigger {
    /// Nothing.
    None,
    /// A data segment completed: an update is due ([`LiveFit::update`]).
    Update,
    /// The procedure completed: the final update is due ([`LiveFit::finish`]).
    Final,
}

/// The live fit.
#[derive(Debug)]
pub struct LiveFit {
    cfg: LiveFitConfig,
    segmenter: Segmenter,
    /// States not yet in force: a state stamped t governs the samples stamped t and later, as
    /// when a log is read (so the live and the offline fit cut the same segments).
    states: VecDeque<ProcedureState>,
    current: Option<ProcedureState>,
    /// The latest sample, held back until the states stamped at or before it have arrived (the
    /// sequencer publishes the state of time t after the sample of time t).
    pending: Option<RigSample>,
    /// Shared with the update in flight, if any: a segment completing while an update runs
    /// copies the data once (`Arc::make_mut`); otherwise an update costs no copy of it.
    data: Arc<Dataset>,
    /// Segments completed since the last update.
    new_segments: usize,
    last_segment: String,
    /// `ProcedureState.sweep_index` of the segment being recorded, and of the newest completed
    /// one that makes an update due: `model/covariance` says which data its model has seen, so
    /// an adaptive sequencer knows when the model includes the sweep it just ran.
    open_sweep_index: u32,
    last_sweep_index: u32,
    /// The latest finished update: stamp, index, sweep index and name of its newest segment.
    last_done: Option<(Time, u32, u32, String)>,
    stamp: Time,
    previous: Option<Arc<FitResult>>,
    /// The uncertainty maps of `previous`.
    maps: Vec<PredictionMap>,
    /// The warm start of the last update (it remembers the levels every update has seen).
    warm: Option<WarmStart>,
    grid: Option<EnvelopeGrid>,
    updates: u32,
    completed: bool,
}

impl LiveFit {
    /// A live fit with no data yet.
    pub fn new(cfg: LiveFitConfig) -> Self {
        let data = Dataset { fnomin_n: cfg.fz0_n, sources: vec!["live".into()], ..Dataset::default() };
        LiveFit {
            cfg,
            segmenter: Segmenter::default(),
            states: VecDeque::new(),
            current: None,
            pending: None,
            data: Arc::new(data),
            new_segments: 0,
            last_segment: String::new(),
            open_sweep_index: 0,
            last_sweep_index: 0,
            last_done: None,
            stamp: Time::default(),
            previous: None,
            maps: Vec::new(),
            warm: None,
            grid: None,
            updates: 0,
            completed: false,
        }
    }

    /// Takes a procedure state. Returns [`Trigger::Final`] when the procedure has completed.
    pub fn on_procedure_state(&mut self, st: &ProcedureState) -> Trigger {
        self.states.push_back(st.clone());
        if st.phase == ProcedureState::PHASE_COMPLETE && !self.completed {
            self.completed = true;
            return Trigger::Final;
        }
        Trigger::None
    }

    /// Takes a rig sample. Returns [`Trigger::Update`] when a data segment has completed since
    /// the last update.
    pub fn on_sample(&mut self, s: &RigSample) -> Trigger {
        if let Some(prev) = self.pending.replace(s.clone()) {
            self.feed(&prev);
        }
        if self.new_segments > 0 { Trigger::Update } else { Trigger::None }
    }

    fn feed(&mut self, s: &RigSample) {
        let t = s.header.stamp.as_secs_f64();
        while self.states.front().is_some_and(|st| st.header.stamp.as_secs_f64() <= t) {
            self.current = self.states.pop_front();
        }
        let Some(st) = self.current.as_ref() else { return };
        let (open_index, state_index) = (self.open_sweep_index, st.sweep_index);
        if let Some(seg) = self.segmenter.push(st, s) {
            self.stamp = s.header.stamp;
            self.add(seg, open_index);
        }
        if self.segmenter.in_segment() {
            self.open_sweep_index = state_index;
        }
    }

    fn add(&mut self, seg: Segment, sweep_index: u32) {
        // Warm-up sweeps are never fitted; they do not make an update due.
        if seg.kind != DataKind::WarmUp {
            self.new_segments += 1;
            self.last_segment = format!("{}/{}", seg.section, seg.sweep);
            self.last_sweep_index = sweep_index;
        }
        Arc::make_mut(&mut self.data).segments.push(seg);
    }

    /// True when a segment has completed since the last update.
    pub fn update_due(&self) -> bool {
        self.new_segments > 0
    }

    /// True once the procedure has completed.
    pub fn completed(&self) -> bool {
        self.completed
    }

    /// The data so far (segments as the offline fit reads them from the log).
    pub fn data(&self) -> &Dataset {
        &self.data
    }

    /// The latest successful fit.
    pub fn latest(&self) -> Option<&FitResult> {
        self.previous.as_deref()
    }

    /// The latest finished update's index and the `sweep_index` of the newest segment in its
    /// data (what `model/covariance` says).
    pub fn latest_reach(&self) -> Option<(u32, u32)> {
        self.last_done.as_ref().map(|(_, index, sweep_index, _)| (*index, *sweep_index))
    }

    /// The `model/covariance` that goes with the latest update's `model/state` (same stamp and
    /// index): the whole model with each stage's covariance, and how far its data reach. Before
    /// the first update: no model, index 0.
    pub fn model_covariance(&self) -> ModelCovariance {
        let mut msg = match self.previous.as_deref() {
            Some(result) => adaptive::wire::to_msg(&ModelSnapshot::of(result)),
            None => ModelCovariance::default(),
        };
        if let Some((stamp, index, sweep_index, last_sweep)) = &self.last_done {
            msg.header.stamp = *stamp;
            msg.update_index = *index;
            msg.last_sweep_index = *sweep_index;
            msg.last_sweep = last_sweep.clone();
        }
        msg.header.frame_id = "iso_w".into();
        msg
    }

    /// Refits on all data so far, warm-started from the previous update, and returns the model
    /// state. A failed update (no usable data yet) keeps the previous model and says why.
    pub fn update(&mut self) -> ModelState {
        let job = self.begin_update();
        self.end_update(job.run())
    }

    /// The work of an update, to run wherever the caller likes (the DDS shell runs it on a
    /// blocking thread while samples keep arriving): all data so far and the previous solution.
    pub fn begin_update(&mut self) -> UpdateJob {
        self.new_segments = 0;
        self.updates += 1;
        let mut opts = self.cfg.update_options(false);
        opts.warm_start = self.previous.as_deref().map(|r| WarmStart::of(r).remembering(self.warm.as_ref()));
        self.warm = opts.warm_start.clone();
        UpdateJob {
            previous: self.previous.clone().map(|r| (r, self.maps.clone())),
            data: self.data.clone(),
            fresh_opts: mffit::FitOptions { warm_start: None, ..opts.clone() },
            opts,
            grid: self.grid.clone(),
            p0_pa: self.cfg.p0_pa,
            index: self.updates,
            last_segment: self.last_segment.clone(),
            last_sweep_index: self.last_sweep_index,
            stamp: self.stamp,
            final_update: false,
        }
    }

    /// Takes a finished update: keeps its fit (a failed one keeps the previous) and returns the
    /// model state.
    pub fn end_update(&mut self, done: UpdateDone) -> ModelState {
        let error = match done.result {
            Ok(result) => {
                self.previous = Some(Arc::new(result));
                self.maps = done.maps;
                String::new()
            }
            // The previous model and its maps stand.
            Err(e) => e,
        };
        if self.grid.is_none() {
            self.grid = done.grid.clone();
        }
        self.last_done = Some((done.stamp, done.index, done.last_sweep_index, done.last_segment.clone()));
        let mut st = model_state(self.previous.as_deref(), self.grid.as_ref(), &self.maps);
        st.header.stamp = done.stamp;
        st.header.frame_id = "iso_w".into();
        st.update_index = done.index;
        st.sweeps_used = done.sweeps_used;
        st.segments_used = done.segments_used;
        st.last_sweep = done.last_segment;
        st.update_wall_s = done.wall_s;
        st.final_update = done.final_update;
        st.error = error;
        st
    }

    /// The final update at the procedure's end: closes the open segment and returns the job;
    /// its state comes out marked final, and [`LiveFit::latest`] is then the fit the shell
    /// writes as `.tir` and report.
    pub fn begin_final(&mut self) -> UpdateJob {
        if let Some(prev) = self.pending.take() {
            self.feed(&prev);
        }
        while let Some(st) = self.states.pop_front() {
            if st.header.stamp.as_secs_f64() > self.stamp.as_secs_f64() {
                self.stamp = st.header.stamp;
            }
            self.current = Some(st);
        }
        if let Some(seg) = self.segmenter.finish() {
            self.add(seg, self.open_sweep_index);
        }
        self.completed = true;
        let mut job = self.begin_update();
        job.final_update = true;
        let final_opts = self.cfg.update_options(true);
        // The warm fit keeps the updates' one-sided Jacobians; the fresh fit it is compared
        // with is the offline fit's, option for option.
        job.opts.max_iterations = final_opts.max_iterations;
        job.opts.restarts = final_opts.restarts;
        job.fresh_opts = final_opts;
        job
    }

    /// [`LiveFit::begin_final`] run at once.
    pub fn finish(&mut self) -> ModelState {
        let job = self.begin_final();
        self.end_update(job.run())
    }
}

/// One update's work ([`LiveFit::begin_update`]); [`UpdateJob::run`] is pure and may run on
/// another thread.
#[derive(Debug)]
pub struct UpdateJob {
    /// The previous fit and its maps: the maps of channels it left unchanged are taken over.
    previous: Option<(Arc<FitResult>, Vec<PredictionMap>)>,
    data: Arc<Dataset>,
    opts: mffit::FitOptions,
    /// The options of a fresh fit of all data, when one runs.
    fresh_opts: mffit::FitOptions,
    grid: Option<EnvelopeGrid>,
    p0_pa: Option<f64>,
    index: u32,
    last_segment: String,
    last_sweep_index: u32,
    stamp: Time,
    final_update: bool,
}

/// What an update gave ([`LiveFit::end_update`] takes it).
#[derive(Debug)]
pub struct UpdateDone {
    result: Result<FitResult, String>,
    grid: Option<EnvelopeGrid>,
    maps: Vec<mffit::prediction::PredictionMap>,
    index: u32,
    last_segment: String,
    last_sweep_index: u32,
    stamp: Time,
    final_update: bool,
    sweeps_used: u32,
    segments_used: u32,
    wall_s: f64,
}

impl UpdateJob {
    /// True for the final update.
    pub fn is_final(&self) -> bool {
        self.final_update
    }

    /// Fits and maps the uncertainty.
    pub fn run(self) -> UpdateDone {
        let started = std::time::Instant::now();
        let fresh = || mffit::fit(&self.data, &self.fresh_opts);
        let result = if self.final_update {
            // The final update always compares with a fresh fit: both fits at once (each is
            // mostly one thread's work between its parallel Jacobians).
            let (warm, cold) = std::thread::scope(|scope| {
                let cold = scope.spawn(fresh);
                (mffit::fit(&self.data, &self.opts), cold.join())
            });
            let cold = cold.unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            polish(warm, cold, "final model")
        } else {
            let warm = mffit::fit(&self.data, &self.opts);
            match warm
                .as_ref()
                .ok()
                .and_then(|r| r.wants_fresh_fit())
                .map(|stage| format!("{stage} {UPSTREAM_NOTE}; kept"))
            {
                Some(why) => polish(warm, fresh(), &why),
                None => warm,
            }
        };
        let mut grid = self.grid;
        let mut maps = Vec::new();
        if let Ok(r) = &result {
            let n = &r.nominal;
            let g =
                grid.get_or_insert_with(|| EnvelopeGrid::standard(n.fz0_n, self.p0_pa.unwrap_or(n.p0_pa), n.v0_mps));
            let previous = self.previous.as_ref().map(|(p, m)| (p.as_ref(), m.as_slice()));
            maps = prediction_maps_since(r, g, previous, self.opts.threads);
        }
        // The whole update: the fit, the fresh-fit comparison when one ran, and the maps.
        let wall_s = started.elapsed().as_secs_f64();
        let segs = &self.data.segments;
        UpdateDone {
            result: result.map_err(|e| e.to_string()),
            grid,
            maps,
            index: self.index,
            last_segment: self.last_segment,
            last_sweep_index: self.last_sweep_index,
            stamp: self.stamp,
            final_update: self.final_update,
            sweeps_used: segs.iter().filter(|s| matches!(s.kind, DataKind::Sweep | DataKind::OnCentre)).count() as u32,
            segments_used: segs.iter().filter(|s| s.kind != DataKind::WarmUp).count() as u32,
            wall_s,
        }
    }
}

/// Sum of the point stages' NRMSE (% of their peaks) over the stages both fits fitted: which of
/// two models of the same data fits them better.
fn score(r: &FitResult, other: &FitResult) -> f64 {
    r.stages
        .iter()
        .filter(|s| s.stage != "relaxation" && r.fitted(&s.stage) && other.fitted(&s.stage))
        .map(|s| s.nrmse_pct())
        .filter(|v| v.is_finite())
        .sum()
}

/// The stage where two fits of the same data differ most, in words.
fn widest_gap(warm: &FitResult, fresh: &FitResult) -> String {
    let nrmse = |r: &FitResult, stage: &str| {
        r.stages.iter().find(|s| s.stage == stage && r.fitted(stage)).map(|s| s.nrmse_pct())
    };
    warm.stages
        .iter()
        .filter(|s| s.stage != "relaxation")
        .filter_map(|s| Some((s.stage.as_str(), nrmse(warm, &s.stage)?, nrmse(fresh, &s.stage)?)))
        .filter(|(_, w, c)| w.is_finite() && c.is_finite())
        .max_by(|a, b| (a.1 - a.2).abs().total_cmp(&(b.1 - b.2).abs()))
        .map_or("no stage fitted by both".into(), |(s, w, c)| format!("widest gap {s}: {w:.3} % vs {c:.3} %"))
}

/// The final model — and the model of an update whose warm start left a stage worse than its last
/// fresh fit even after refitting that stage ([`UPSTREAM_NOTE`]) — is the warm-started one, or a
/// fresh fit of all data (as `tyrerig fit` makes it) when that fits the data better. Warm starts
/// carry the path the data took: a coefficient set found on the first sweeps can sit in a local
/// minimum that a fresh start avoids. Which one was kept, and `why` the comparison ran, is the
/// first of the fit's warnings.
fn polish(
    warm: Result<FitResult, mffit::FitError>,
    cold: Result<FitResult, mffit::FitError>,
    why: &str,
) -> Result<FitResult, mffit::FitError> {
    match (warm, cold) {
        (Ok(w), Ok(c)) => {
            let (sw, sc) = (score(&w, &c), score(&c, &w));
            let keep_warm = sw <= sc;
            let note = format!(
                "{why}: {} (sum of stage NRMSE: warm-started {sw:.3} %, fresh fit {sc:.3} %; {})",
                if keep_warm { "warm-started" } else { "fresh fit" },
                widest_gap(&w, &c)
            );
            let both_s = w.wall_s + c.wall_s;
            let mut kept = if keep_warm { w } else { c };
            kept.warnings.insert(0, note);
            kept.wall_s = both_s;
            Ok(kept)
        }
        (Ok(w), Err(_)) => Ok(w),
        (Err(_), c) => c,
    }
}
