//! The node's shell: DDS in, Foxglove WebSocket out (and, when the launch file allows it,
//! operator commands from Foxglove clients back onto `procedure/command`).
//!
//! One DDS subscription task per suite topic takes each message as it arrives, encodes it to
//! CDR once and hands it to the SDK's channel. The SDK queues a copy per subscribed client and,
//! when a client's queue is full, drops that client's oldest messages: nothing here ever waits
//! for a browser, so a slow or stuck client drops its own frames and never slows the suite.

use crate::command::CommandGate;
use crate::config::{FoxgloveConfigError, FoxgloveNodeConfig};
use crate::core::{Input, ViewCore, ViewMessage};
use crate::latch::Latch;
use crate::views::{PlanView, View};
use foxglove::websocket::{Capability, ChannelView, Client, ClientChannel, ServerListener, Status};
use foxglove::{ChannelBuilder, ChannelId, Context, PartialMetadata, RawChannel, Schema, WebSocketServer};
use futures::StreamExt;
use node_runtime::{RosNode, RuntimeError, Shutdown, SuiteTopic, topics::TopicVisitor};
use std::any::Any;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use tokio::sync::mpsc;
use tyre_msgs::diagnostic_msgs::DiagnosticArray;
use tyre_msgs::{ModelState, ProcedureCommand, ProcedureState, QualityReport, RigSample, RosMessage, ThermalState};

/// Why the node stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum FoxgloveNodeError {
    #[error("foxglove config: {0}")]
    Config(#[from] FoxgloveConfigError),
    #[error("{path}: procedure: {detail}")]
    Procedure { path: String, detail: String },
    #[error("foxglove: topic {topic}: no ros2msg schema: {detail}")]
    Schema { topic: String, detail: String },
    #[error("foxglove: channel {topic}: {detail}")]
    Channel { topic: String, detail: String },
    #[error("foxglove: cannot serve on {host}:{port}: {detail}")]
    Server { host: String, port: u16, detail: String },
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
}

/// What the node did, returned when it stops.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FoxgloveStats {
    /// Messages taken from DDS per topic (full name).
    pub taken: BTreeMap<String, u64>,
    /// Client commands published onto `procedure/command`.
    pub commands_sent: u64,
    /// Client commands refused.
    pub commands_refused: u64,
    /// The port the server listened on.
    pub port: u16,
}

/// The plan view of a procedure file expanded as the sequencer expands it.
pub fn plan_view(cfg: &FoxgloveNodeConfig, procedure: &Path) -> Result<PlanView, FoxgloveNodeError> {
    let err = |detail: String| FoxgloveNodeError::Procedure { path: procedure.display().to_string(), detail };
    let doc = procedure::load(procedure).map_err(|e| err(e.to_string()))?;
    let inputs = procedure::RunInputs { load_index: cfg.load_index, sweeps: cfg.sweeps, ..Default::default() };
    let plan = procedure::expand(&doc, &inputs).map_err(|e| err(e.to_string()))?;
    Ok(PlanView::from_plan(&plan, &procedure::PauseModel::default()))
}

/// A server channel and what a late subscriber to it is sent.
#[derive(Debug, Clone, Copy)]
enum Latched {
    Suite(SuiteTopic),
    View(View),
}

/// State shared by the DDS tasks, the view ticker and the server's callbacks.
struct Shared {
    core: Mutex<ViewCore>,
    suite_latch: Mutex<Latch<SuiteTopic>>,
    suite: BTreeMap<SuiteTopic, Arc<RawChannel>>,
    views: BTreeMap<View, Arc<RawChannel>>,
    by_id: HashMap<ChannelId, Latched>,
    gate: CommandGate,
    commands: mpsc::UnboundedSender<ProcedureCommand>,
    commands_refused: AtomicU64,
}

impl Shared {
    fn emit(&self, out: Vec<ViewMessage>) {
        for m in out {
            if let Some(ch) = self.views.get(&m.view) {
                ch.log_with_meta(&m.json, PartialMetadata { log_time: Some(m.log_time_ns) });
            }
        }
    }

    fn core(&self) -> std::sync::MutexGuard<'_, ViewCore> {
        // A panic while holding the lock would be a bug in the core; keep serving regardless.
        self.core.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn rig_time_ns(&self) -> u64 {
        (self.core().rig_time_s().max(0.0) * 1e9) as u64
    }
}

/// How many messages of a suite topic a late subscriber is sent: what DDS durability keeps.
fn suite_latch_depth(topic: SuiteTopic) -> usize {
    use node_runtime::Qos;
    match topic.spec().qos {
        Qos::State | Qos::Diagnostics => 1,
        Qos::Events => 1000,
        Qos::Stream | Qos::Command | Qos::Clock => 0,
    }
}

/// The stamp every suite message starts with (first 8 bytes after the encapsulation header).
fn stamp_ns(cdr: &[u8]) -> Option<u64> {
    let sec = i32::from_le_bytes(cdr.get(4..8)?.try_into().ok()?);
    let nanosec = u32::from_le_bytes(cdr.get(8..12)?.try_into().ok()?);
    (sec > 0 || nanosec > 0).then(|| u64::try_from(sec).ok().map(|s| s * 1_000_000_000 + u64::from(nanosec)))?
}

struct Listener {
    shared: Arc<Shared>,
}

impl ServerListener for Listener {
    fn on_subscribe(&self, client: Client, channel: ChannelView) {
        let replay = match self.shared.by_id.get(&channel.id()) {
            Some(Latched::Suite(t)) => {
                let kept = self.shared.suite_latch.lock().unwrap_or_else(|p| p.into_inner()).replay(*t);
                self.shared.suite.get(t).map(|ch| (ch.clone(), kept))
            }
            Some(Latched::View(v)) => {
                let kept = self.shared.core().latched(*v);
                self.shared.views.get(v).map(|ch| (ch.clone(), kept))
            }
            None => None,
        };
        if let Some((ch, kept)) = replay {
            for (t, payload) in kept {
                ch.log_with_meta_to_sink(&payload, PartialMetadata { log_time: Some(t) }, client.sink_id());
            }
        }
    }

    fn on_client_advertise(&self, client: Client, channel: &ClientChannel) {
        if let Err(why) = self.shared.gate.check_channel(&channel.topic, &channel.encoding, &channel.schema_name) {
            client.send_status(Status::warning(why));
        }
    }

    fn on_message_data(&self, client: Client, channel: &ClientChannel, payload: &[u8]) {
        let who = format!("foxglove client {}", client.id());
        let rig_time_s = self.shared.core().rig_time_s();
        let verdict = self
            .shared
            .gate
            .judge(&channel.topic, &channel.encoding, &channel.schema_name, payload, &who, rig_time_s)
            .and_then(|cmd| {
                self.shared.commands.send(cmd.clone()).map(|()| cmd).map_err(|_| "the node is stopping".to_owned())
            });
        match &verdict {
            Ok(_) => tracing::info!("{who}: command accepted"),
            Err(why) => {
                self.shared.commands_refused.fetch_add(1, Ordering::Relaxed);
                tracing::warn!("{who}: command refused: {why}");
                client.send_status(Status::warning(why.clone()));
            }
        }
        let out = self.shared.core().on_command(&who, &verdict);
        self.shared.emit(out);
    }
}

/// Runs the node until `shutdown`.
pub async fn run(
    mut node: RosNode,
    cfg: FoxgloveNodeConfig,
    shutdown: Shutdown,
) -> Result<FoxgloveStats, FoxgloveNodeError> {
    cfg.validate()?;
    let plan = cfg.procedure.as_deref().map(|p| plan_view(&cfg, p)).transpose()?;
    let ns = node.namespace().to_owned();
    let ctx = Context::new();
    let channel_err = |topic: &str, e: foxglove::FoxgloveError| FoxgloveNodeError::Channel {
        topic: topic.to_owned(),
        detail: e.to_string(),
    };

    let mut suite = BTreeMap::new();
    let mut by_id = HashMap::new();
    for t in SuiteTopic::ALL {
        let name = t.full_name(&ns);
        let schema = tyre_msgs::schema::ros2msg_schema_for(&t.ros_type_name())
            .map_err(|e| FoxgloveNodeError::Schema { topic: name.clone(), detail: e.to_string() })?;
        let ch = ChannelBuilder::new(&name)
            .message_encoding("cdr")
            .schema(Schema::new(t.ros_type_name(), "ros2msg", schema.into_bytes()))
            .context(&ctx)
            .build_raw()
            .map_err(|e| channel_err(&name, e))?;
        by_id.insert(ch.id(), Latched::Suite(t));
        suite.insert(t, ch);
    }
    let mut views = BTreeMap::new();
    for v in View::ALL {
        let name = v.full_name(&ns);
        let ch = ChannelBuilder::new(&name)
            .message_encoding("json")
            .schema(Schema::new(v.schema_name(), "jsonschema", v.json_schema().into_bytes()))
            .context(&ctx)
            .build_raw()
            .map_err(|e| channel_err(&name, e))?;
        by_id.insert(ch.id(), Latched::View(v));
        views.insert(v, ch);
    }

    let gate = CommandGate::new(cfg.allowed_codes(), SuiteTopic::ProcedureCommand.full_name(&ns));
    let (cmd_tx, mut cmd_rx) = mpsc::unbounded_channel();
    let shared = Arc::new(Shared {
        core: Mutex::new(ViewCore::new(plan, cfg.trace_max_points)),
        suite_latch: Mutex::new(Latch::new(SuiteTopic::ALL.map(|t| (t, suite_latch_depth(t))))),
        suite,
        views,
        by_id,
        gate: gate.clone(),
        commands: cmd_tx,
        commands_refused: AtomicU64::new(0),
    });
    let start = shared.core().start();
    shared.emit(start);

    let mut server = WebSocketServer::new()
        .name(format!("tyrerig {ns}"))
        .bind(&cfg.host, cfg.port)
        .context(&ctx)
        .message_backlog_size(cfg.message_backlog)
        .listener(Arc::new(Listener { shared: shared.clone() }));
    if gate.any_allowed() {
        server = server.capabilities([Capability::ClientPublish]).supported_encodings(["cdr"]);
    }
    let handle = server.start().await.map_err(|e| FoxgloveNodeError::Server {
        host: cfg.host.clone(),
        port: cfg.port,
        detail: e.to_string(),
    })?;
    let port = handle.port();
    tracing::info!(
        "foxglove: serving {} topics on ws://{}:{port} (open it in Foxglove: Open connection → Foxglove WebSocket; layout launch-config/foxglove/tyre-rig.json){}",
        SuiteTopic::ALL.len() + View::ALL.len(),
        cfg.host,
        if gate.any_allowed() {
            format!("; clients may send {}", gate.allowed_names().join(", "))
        } else {
            String::new()
        }
    );

    // DDS → Foxglove, one task per topic.
    let mut tasks = Vec::new();
    let mut counters = Vec::new();
    for t in SuiteTopic::ALL {
        let taken = Arc::new(AtomicU64::new(0));
        counters.push((t.full_name(&ns), taken.clone()));
        tasks.push(t.visit(Forward { node: &mut node, shared: shared.clone(), taken, shutdown: shutdown.clone() })?);
    }
    // Client commands → DDS, only when some are allowed.
    let publisher =
        if gate.any_allowed() { Some(node.publisher::<ProcedureCommand>(SuiteTopic::ProcedureCommand)?) } else { None };
    let mut commands_sent = 0u64;
    let mut ticker = tokio::time::interval(std::time::Duration::from_secs_f64(1.0 / cfg.view_rate_hz));
    ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    loop {
        tokio::select! {
            _ = shutdown.wait() => break,
            _ = ticker.tick() => {
                let out = shared.core().tick();
                shared.emit(out);
            }
            Some(cmd) = cmd_rx.recv() => {
                if let Some(p) = &publisher {
                    match p.publish(cmd) {
                        Ok(()) => commands_sent += 1,
                        Err(e) => tracing::error!("foxglove: publishing a client command failed: {e:?}"),
                    }
                }
            }
        }
    }
    for t in tasks {
        let _ = t.await;
    }
    // Stop accepting clients and close the ones connected.
    let stopping = handle.stop();
    let _ = tokio::time::timeout(std::time::Duration::from_secs(2), stopping.wait()).await;
    let stats = FoxgloveStats {
        taken: counters.into_iter().map(|(n, c)| (n, c.load(Ordering::Relaxed))).collect(),
        commands_sent,
        commands_refused: shared.commands_refused.load(Ordering::Relaxed),
        port,
    };
    tracing::info!(?stats, "foxglove: stopped");
    Ok(stats)
}

/// The view input a suite message is, if the views use it.
fn as_input<M: Any>(msg: &M) -> Option<Input<'_>> {
    let any = msg as &dyn Any;
    if let Some(s) = any.downcast_ref::<RigSample>() {
        return Some(Input::Sample(s));
    }
    if let Some(s) = any.downcast_ref::<ProcedureState>() {
        return Some(Input::State(s));
    }
    if let Some(s) = any.downcast_ref::<ThermalState>() {
        return Some(Input::Thermal(s));
    }
    if let Some(s) = any.downcast_ref::<QualityReport>() {
        return Some(Input::Quality(s));
    }
    if let Some(s) = any.downcast_ref::<ModelState>() {
        return Some(Input::Model(s));
    }
    any.downcast_ref::<DiagnosticArray>().map(Input::Diagnostics)
}

struct Forward<'a> {
    node: &'a mut RosNode,
    shared: Arc<Shared>,
    taken: Arc<AtomicU64>,
    shutdown: Shutdown,
}

impl TopicVisitor for Forward<'_> {
    type Output = Result<tokio::task::JoinHandle<()>, RuntimeError>;
    fn visit<M: RosMessage + Send + Sync + 'static>(self, topic: SuiteTopic) -> Self::Output {
        let sub = self.node.subscription::<M>(topic)?;
        let Forward { shared, taken, shutdown, .. } = self;
        let channel = shared.suite[&topic].clone();
        let latched = suite_latch_depth(topic) > 0;
        Ok(tokio::spawn(async move {
            let mut stream = Box::pin(sub.async_stream());
            loop {
                let item = tokio::select! {
                    _ = shutdown.wait() => break,
                    item = stream.next() => item,
                };
                let msg = match item {
                    Some(Ok((msg, _))) => msg,
                    Some(Err(e)) => {
                        tracing::warn!("foxglove: {topic:?}: receive error: {e:?}");
                        continue;
                    }
                    None => break,
                };
                taken.fetch_add(1, Ordering::Relaxed);
                // Encode only when someone looks (or a late joiner will): CDR, as DDS carried it.
                if latched || channel.has_sinks() {
                    match tyre_msgs::cdr::to_cdr_with_header(&msg) {
                        Ok(bytes) => {
                            let log_time = stamp_ns(&bytes).unwrap_or_else(|| shared.rig_time_ns());
                            if latched {
                                shared
                                    .suite_latch
                                    .lock()
                                    .unwrap_or_else(|p| p.into_inner())
                                    .keep(topic, log_time, &bytes);
                            }
                            channel.log_with_meta(&bytes, PartialMetadata { log_time: Some(log_time) });
                        }
                        Err(e) => tracing::error!("foxglove: {topic:?}: cannot encode: {e}"),
                    }
                }
                if let Some(input) = as_input(&msg) {
                    let out = shared.core().on_input(input);
                    shared.emit(out);
                }
            }
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_are_read_from_the_cdr_and_zero_means_none() {
        let s = RigSample {
            header: tyre_msgs::std_msgs::Header {
                stamp: tyre_msgs::builtin_interfaces::Time { sec: 3, nanosec: 500 },
                ..Default::default()
            },
            ..RigSample::default()
        };
        let bytes = tyre_msgs::cdr::to_cdr_with_header(&s).expect("cdr");
        assert_eq!(stamp_ns(&bytes), Some(3_000_000_500));
        let zero = tyre_msgs::cdr::to_cdr_with_header(&RigSample::default()).expect("cdr");
        assert_eq!(stamp_ns(&zero), None);
        assert_eq!(stamp_ns(&[0, 1]), None);
    }

    #[test]
    fn late_joiners_get_what_dds_durability_keeps() {
        assert_eq!(suite_latch_depth(SuiteTopic::ProcedureState), 1);
        assert_eq!(suite_latch_depth(SuiteTopic::SweepSummary), 1000);
        assert_eq!(suite_latch_depth(SuiteTopic::RigSample), 0);
    }
}
