//! The DDS shell: setpoints in, samples and `/clock` out.

use futures::StreamExt;
use node_runtime::{RosNode, RuntimeError, Shutdown, SuiteTopic};
use rigsim::{RigConfig, TyreParams, VirtualRig};
use serde::Deserialize;
use std::{path::PathBuf, time::Duration};
use tyre_msgs::{RigSample, RigSetpoint, rosgraph_msgs::Clock};

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
    if let Some(e) = &cfg.effects {
        rc.effects = rigsim::Effects::parse(e).map_err(|e| VirtualRigNodeError::Rig(format!("effects: {e}")))?;
    }
    let params = TyreParams::read_tir(&rc.tyre_file)
        .map_err(|e| VirtualRigNodeError::Rig(format!("{}: {e}", rc.tyre_file.display())))?;
    let seed = cfg.seed.unwrap_or(rc.seed);
    VirtualRig::new(rc, params, seed).map_err(|e| VirtualRigNodeError::Rig(e.to_string()))
}

/// Runs the rig until shutdown (or `max_sim_time_s`).
pub async fn run(mut node: RosNode, cfg: VirtualRigNodeConfig, shutdown: Shutdown) -> Result<(), VirtualRigNodeError> {
    cfg.validate()?;
    let mut rig = build_rig(&cfg)?;
    let samples = node.publisher::<RigSample>(SuiteTopic::RigSample)?;
    let clock = node.publisher::<Clock>(SuiteTopic::Clock)?;
    let setpoints = node.subscription::<RigSetpoint>(SuiteTopic::RigSetpoint)?;
    let mut setpoint_stream = Box::pin(setpoints.async_stream());
    // A reliable writer whose history is full (a slow subscriber) reports WouldBlock after its
    // wait: that is back-pressure, not a fault — the rig holds the sample and tries again, and
    // gives up only after ~10 s of refusals (a subscriber that is gone for good).
    let publish = |s: &RigSample| -> Result<(), VirtualRigNodeError> {
        let mut tries = 0u32;
        while let Err(e) = samples.publish(s.clone()) {
            tries += 1;
            if tries >= 50 {
                return Err(VirtualRigNodeError::Publish { topic: "sample", detail: format!("{e:?}") });
            }
        }
        let _ = clock.publish(Clock { clock: s.header.stamp });
        Ok(())
    };
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
                while let Some(Some(Ok((sp, _)))) = futures::FutureExt::now_or_never(setpoint_stream.next()) {
                    apply(&mut rig, &sp);
                }
            }
            ClockMode::Lockstep => {
                // Wait for the answer to this sample (setpoint stamped >= its time).
                let deadline = tokio::time::Instant::now() + Duration::from_secs_f64(cfg.lockstep_timeout_s);
                loop {
                    tokio::select! {
                        _ = shutdown.wait() => break,
                        _ = tokio::time::sleep_until(deadline) => break,
                        item = setpoint_stream.next() => match item {
                            Some(Ok((sp, _))) => {
                                let answered = sp.header.stamp >= t;
                                apply(&mut rig, &sp);
                                if answered {
                                    break;
                                }
                            }
                            Some(Err(e)) => tracing::warn!("setpoint receive error: {e:?}"),
                            None => break,
                        }
                    }
                }
            }
        }
    }
    Ok(())
}
