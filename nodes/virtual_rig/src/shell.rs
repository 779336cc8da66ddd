//! The DDS shell: setpoints in, samples and `/clock` out.
//!
//! The rig has its own watchdog, as a real rig controller does: when setpoints stop coming (the
//! sequencer died, or a lockstep answer never came) it holds zero slip at the present load and
//! speed instead of running on with the last slip it was told. Lost or malformed setpoints are
//! counted and announced on `/diagnostics` (`node_runtime::LossWatch`).
//!
//! Once a wall second, and when it stops, the rig announces its own count of the samples it made
//! (`<node>: published` on `/diagnostics`, a [`WriterTally`]: the last `RigSample.seq`, how many
//! its writer took and how many it refused), so a recorder knows what it did not get even when
//! the stream stops early and no later sample shows a gap.

use futures::StreamExt;
use node_runtime::{LossWatch, RosNode, RuntimeError, Shutdown, SuiteTopic, WriterTally};
use rigsim::{RigConfig, VirtualRig};
use serde::Deserialize;
use std::{path::PathBuf, time::Duration};
use tyre_msgs::{
    RigSample, RigSetpoint,
    diagnostic_msgs::{DiagnosticArray, DiagnosticStatus},
    rosgraph_msgs::Clock,
    std_msgs::Header,
};

/// How simulated time advances.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClockMode {
    Realtime,
    Lockstep,
}

/// `[node.config]` of a virtual_rig node.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VirtualRigNodeConfig {
    /// The rig's config file (`launch-config/virtual_rig.toml`).
    pub rig_config: PathBuf,
    /// Tyre file replacing the config's.
    #[serde(default)]
    pub tyre: Option<PathBuf>,
    /// Effects replacing the config's (`none`, `all` or a comma list).
    #[serde(default)]
    pub effects: Option<String>,
    /// Noise seed (default: the config's).
    #[serde(default)]
    pub seed: Option<u64>,
    /// RigSample rate replacing the config's (e.g. 1000 for a 1 kHz rig) [Hz].
    #[serde(default)]
    pub publish_rate_hz: Option<u32>,
    #[serde(default = "default_clock")]
    pub clock: ClockMode,
    /// Lockstep: how long to wait for the sequencer's answer before going on [s of wall time].
    #[serde(default = "default_timeout")]
    pub lockstep_timeout_s: f64,
    /// Stop after this much simulated time (absent: until shut down) [s].
    #[serde(default)]
    pub max_sim_time_s: Option<f64>,
    /// Wall time to wait before the first sample, so the other nodes discover the rig [s].
    #[serde(default = "default_start_delay")]
    pub start_delay_s: f64,
    /// Realtime clock: simulated seconds per wall second (1 = real time, 10 = ten times
    /// faster; every node follows `/clock` and message stamps, none the wall clock).
    #[serde(default = "default_time_scale")]
    pub time_scale: f64,
    /// Realtime clock: wall time without a setpoint (once setpoints have come) after which the
    /// rig holds zero slip by itself [s]. Lockstep: a missed answer does the same.
    #[serde(default = "default_setpoint_timeout")]
    pub setpoint_timeout_s: f64,
    /// Lockstep clock: at most this many simulated seconds per wall second (absent: as fast as
    /// the sequencer answers). Keeps the subscribers outside the loop (recorder, quality) within
    /// their pace, e.g. on a secured domain.
    #[serde(default)]
    pub max_time_scale: Option<f64>,
    /// Before the first sample, wait until this many subscriptions to `sample` are discovered
    /// (then `start_delay_s` more), so no subscriber misses the start.
    #[serde(default)]
    pub wait_for_subscribers: usize,
}

fn default_setpoint_timeout() -> f64 {
    0.5
}

/// What the rig's watchdog holds: the last setpoint without slip (load, speed, pressure and
/// camber stay, so the tyre neither unloads nor heats).
pub fn zero_slip_hold(last: &RigSetpoint) -> RigSetpoint {
    let mut hold = last.clone();
    hold.slip_angle_deg = 0.0;
    hold.slip_ratio = 0.0;
    hold.belt_displacement_m = 0.0;
    hold.sweep_name = String::new();
    if hold.mode == RigSetpoint::MODE_STATIC {
        hold.mode = RigSetpoint::MODE_FREE_ROLLING;
    }
    hold
}

fn default_time_scale() -> f64 {
    1.0
}

impl VirtualRigNodeConfig {
    /// Checks the values a TOML type check cannot.
    pub fn validate(&self) -> Result<(), VirtualRigNodeError> {
        let positive = |key: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(VirtualRigNodeError::Config { key, detail: format!("{v} (expected a finite value > 0)") })
            }
        };
        positive("time_scale", self.time_scale)?;
        if let Some(m) = self.max_time_scale {
            positive("max_time_scale", m)?;
        }
        positive("lockstep_timeout_s", self.lockstep_timeout_s)?;
        positive("setpoint_timeout_s", self.setpoint_timeout_s)?;
        if !(self.start_delay_s.is_finite() && self.start_delay_s >= 0.0) {
            return Err(VirtualRigNodeError::Config {
                key: "start_delay_s",
                detail: format!("{} (expected a finite value ≥ 0)", self.start_delay_s),
            });
        }
        Ok(())
    }
}

fn default_start_delay() -> f64 {
    2.0
}

fn default_clock() -> ClockMode {
    ClockMode::Realtime
}
fn default_timeout() -> f64 {
    2.0
}

/// Why the node stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum VirtualRigNodeError {
    #[error("virtual rig: {0}")]
    Rig(String),
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
    #[error("virtual rig: publishing on {topic} failed: {detail}")]
    Publish { topic: &'static str, detail: String },
    #[error("virtual rig: `{key}` = {detail}")]
    Config { key: &'static str, detail: String },
}

/// Builds the simulator from the node config.
pub fn build_rig(cfg: &VirtualRigNodeConfig) -> Result<VirtualRig, VirtualRigNodeError> {
    let mut rc = RigConfig::load(&cfg.rig_config).map_err(|e| VirtualRigNodeError::Rig(e.to_string()))?;
    if let Some(t) = &cfg.tyre {
        rc.tyre_file = t.clone();
    }
    if let Some(r) = cfg.publish_rate_hz {
        rc.publish_rate_hz = r;
        rc.validate().map_err(|(key, detail)| VirtualRigNodeError::Rig(format!("publish_rate_hz: {key}: {detail}")))?;
    }
    if let Some(e) = &cfg.effects {
        rc.effects = rigsim::Effects::parse(e).map_err(|e| VirtualRigNodeError::Rig(format!("effects: {e}")))?;
    }
    // An MF .tir or a brush-tyre file, per the rig config's `[tyre] model`.
    let tyre = rigsim::VirtualTyre::load(&rc).map_err(|e| VirtualRigNodeError::Rig(e.to_string()))?;
    let seed = cfg.seed.unwrap_or(rc.seed);
    VirtualRig::new(rc, tyre, seed).map_err(|e| VirtualRigNodeError::Rig(e.to_string()))
}

/// Runs the rig until shutdown (or `max_sim_time_s`).
pub async fn run(mut node: RosNode, cfg: VirtualRigNodeConfig, shutdown: Shutdown) -> Result<(), VirtualRigNodeError> {
    cfg.validate()?;
    let mut rig = build_rig(&cfg)?;
    let samples = node.publisher::<RigSample>(SuiteTopic::RigSample)?;
    let clock = node.publisher::<Clock>(SuiteTopic::Clock)?;
    let setpoints = node.subscription::<RigSetpoint>(SuiteTopic::RigSetpoint)?;
    let diagnostics = node.publisher::<DiagnosticArray>(SuiteTopic::Diagnostics)?;
    let mut setpoint_stream = Box::pin(setpoints.async_stream());
    let setpoint_topic = node.topic_name(SuiteTopic::RigSetpoint);
    let node_name = node.name().to_owned();
    let mut loss = LossWatch::new(node.name());
    let publish_errors = node_runtime::PublishErrors::new();
    // The watchdog: the last setpoint, when it came, and whether the rig holds by itself.
    let mut last_setpoint: Option<(RigSetpoint, std::time::Instant)> = None;
    let mut holding = false;
    let setpoint_timeout = Duration::from_secs_f64(cfg.setpoint_timeout_s);
    let hold = |rig: &mut VirtualRig, last: &RigSetpoint, why: &str, stamp| {
        tracing::warn!("{why}: holding zero slip");
        if let Err(refusal) = rig.apply_setpoint(&zero_slip_hold(last)) {
            tracing::warn!("zero-slip hold refused: {refusal}");
        }
        let status = DiagnosticStatus {
            level: DiagnosticStatus::ERROR,
            name: format!("{node_name}: setpoint_watchdog"),
            message: format!("{why}: the rig holds zero slip"),
            hardware_id: "virtual rig".into(),
            values: Vec::new(),
        };
        publish_errors.check(
            SuiteTopic::Diagnostics,
            diagnostics
                .publish(DiagnosticArray { header: Header { stamp, frame_id: String::new() }, status: vec![status] }),
        );
    };
    // A reliable writer whose send window is full (a reader far behind; one that stopped
    // acknowledging altogether, killed or stopped, is no longer waited for after 2 s:
    // vendor/rustdds patch 3) refuses the sample after at most 1 ms (`Qos::Stream`). The rig never
    // waits on its readers: the sample is dropped, and every reader sees the gap in
    // RigSample.seq and reports it.
    let refused = std::sync::atomic::AtomicU64::new(0);
    let published = std::sync::atomic::AtomicU64::new(0);
    let last_seq = std::sync::atomic::AtomicU64::new(0);
    let publish = |s: &RigSample| -> Result<(), VirtualRigNodeError> {
        last_seq.store(s.seq, std::sync::atomic::Ordering::Relaxed);
        if let Err(e) = samples.publish(s.clone()) {
            let n = refused.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if n <= 5 || n.is_multiple_of(1000) {
                tracing::warn!(
                    "sample seq {} refused by the writer ({} so far): {}",
                    s.seq,
                    n,
                    format!("{e:?}").chars().take(60).collect::<String>()
                );
            }
        } else {
            published.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
        publish_errors.check(SuiteTopic::Clock, clock.publish(Clock { clock: s.header.stamp }));
        Ok(())
    };
    // The rig's own count of its samples, on `/diagnostics` (see the module docs).
    let sample_topic = node.topic_name(SuiteTopic::RigSample);
    let sample_writer = node_runtime::loss::publisher_id(&samples);
    let announce_tally = |stamp| {
        let tally = WriterTally {
            topic: sample_topic.clone(),
            writer: sample_writer,
            last_seq: last_seq.load(std::sync::atomic::Ordering::Relaxed),
            published: published.load(std::sync::atomic::Ordering::Relaxed),
            refused: refused.load(std::sync::atomic::Ordering::Relaxed),
        };
        let d = DiagnosticArray {
            header: Header { stamp, frame_id: String::new() },
            status: vec![tally.to_status(&node_name)],
        };
        if let Err(e) = diagnostics.publish(d) {
            tracing::warn!("/diagnostics publish: {e:?}");
        }
    };
    let mut tally_at = std::time::Instant::now();
    let apply = |rig: &mut VirtualRig, sp: &RigSetpoint| {
        if let Err(refusal) = rig.apply_setpoint(sp) {
            tracing::warn!("setpoint refused, rig safe: {refusal}");
        }
    };
    let mut waited = tokio::time::Instant::now();
    while node.discovered_subscriptions(SuiteTopic::RigSample) < cfg.wait_for_subscribers {
        if waited.elapsed() >= Duration::from_secs(5) {
            let found = node.discovered_subscriptions(SuiteTopic::RigSample);
            tracing::info!("waiting for {} subscribers of sample, {found} so far", cfg.wait_for_subscribers);
            waited = tokio::time::Instant::now();
        }
        tokio::select! {
            _ = shutdown.wait() => return Ok(()),
            _ = tokio::time::sleep(Duration::from_millis(50)) => {}
        }
    }
    tokio::select! {
        _ = shutdown.wait() => return Ok(()),
        _ = tokio::time::sleep(Duration::from_secs_f64(cfg.start_delay_s.max(0.0))) => {}
    }
    let wall_start = tokio::time::Instant::now();
    let sim_start = rig.time_s();
    let mut last_stamp = None;
    tracing::info!(clock = ?cfg.clock, time_scale = cfg.time_scale, "virtual rig running");
    loop {
        if shutdown.is_triggered() || cfg.max_sim_time_s.is_some_and(|m| rig.time_s() - sim_start >= m) {
            break;
        }
        // Integrate to the next sample.
        let sample = loop {
            if let Some(s) = rig.step() {
                break s;
            }
        };
        let pace = match cfg.clock {
            ClockMode::Realtime => Some(cfg.time_scale),
            ClockMode::Lockstep => cfg.max_time_scale,
        };
        if let Some(scale) = pace {
            let due = wall_start + Duration::from_secs_f64((sample.runtime_s - sim_start) / scale);
            tokio::select! {
                _ = shutdown.wait() => break,
                _ = tokio::time::sleep_until(due) => {}
            }
        }
        publish(&sample)?;
        let t = sample.header.stamp;
        match cfg.clock {
            ClockMode::Realtime => {
                // Take whatever setpoints arrived meanwhile, newest last.
                while let Some(Some(item)) = futures::FutureExt::now_or_never(setpoint_stream.next()) {
                    match item {
                        Ok((sp, info)) => {
                            loss.on_message(&setpoint_topic, &info, None);
                            apply(&mut rig, &sp);
                            last_setpoint = Some((sp, std::time::Instant::now()));
                            holding = false;
                        }
                        Err(e) => loss.on_read_error(&setpoint_topic, &e),
                    }
                }
                if !holding
                    && let Some((sp, at)) = &last_setpoint
                    && at.elapsed() >= setpoint_timeout
                {
                    hold(&mut rig, sp, &format!("no setpoint for {:.1} s", at.elapsed().as_secs_f64()), t);
                    holding = true;
                }
            }
            ClockMode::Lockstep => {
                // Wait for the answer to this sample (setpoint stamped >= its time).
                let deadline = tokio::time::Instant::now() + Duration::from_secs_f64(cfg.lockstep_timeout_s);
                let mut answered = false;
                loop {
                    tokio::select! {
                        _ = shutdown.wait() => break,
                        _ = tokio::time::sleep_until(deadline) => break,
                        item = setpoint_stream.next() => match item {
                            Some(Ok((sp, info))) => {
                                loss.on_message(&setpoint_topic, &info, None);
                                answered = sp.header.stamp >= t;
                                apply(&mut rig, &sp);
                                last_setpoint = Some((sp, std::time::Instant::now()));
                                holding = false;
                                if answered {
                                    break;
                                }
                            }
                            Some(Err(e)) => loss.on_read_error(&setpoint_topic, &e),
                            None => break,
                        }
                    }
                }
                if !answered
                    && !holding
                    && !shutdown.is_triggered()
                    && let Some((sp, _)) = &last_setpoint
                {
                    let why = format!(
                        "no answer to the sample at {:.3} s within {} s",
                        t.as_secs_f64(),
                        cfg.lockstep_timeout_s
                    );
                    hold(&mut rig, sp, &why, t);
                    holding = true;
                }
            }
        }
        loss.announce(&diagnostics, t);
        if tally_at.elapsed() >= TALLY_EVERY {
            announce_tally(t);
            tally_at = std::time::Instant::now();
        }
        last_stamp = Some(t);
    }
    if let Some(t) = last_stamp {
        announce_tally(t);
        // The closing count is what a recorder's loss record measures its missing tail by: the
        // participant stays until every reader has it and the last samples.
        node.flush_before_exit(&[
            (SuiteTopic::Diagnostics, diagnostics.guid()),
            (SuiteTopic::RigSample, samples.guid()),
        ])
        .await;
    }
    Ok(())
}

/// How often the rig announces its count of samples (wall time).
pub const TALLY_EVERY: Duration = Duration::from_secs(1);
