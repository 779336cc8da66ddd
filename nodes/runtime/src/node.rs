//! [`RosNode`]: one DDS participant + one ROS 2 node, with typed endpoints from the topic table.

use crate::{RuntimeConfig, RuntimeConfigError, SecurityConfigError, SuiteTopic};
use ros2_client::{
    Context, ContextOptions, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher, Subscription,
};
use tyre_msgs::RosMessage;

/// Something DDS refused to do, named by node and topic.
#[derive(Debug, thiserror::Error)]
pub enum RuntimeError {
    #[error(transparent)]
    Config(#[from] RuntimeConfigError),
    #[error(transparent)]
    Security(#[from] SecurityConfigError),
    #[error("node {node:?}: could not create the DDS participant on domain {domain_id}: {detail}")]
    Participant { node: String, domain_id: u16, detail: String },
    #[error("node {node:?}: invalid node name or namespace: {detail}")]
    Name { node: String, detail: String },
    #[error("node {node:?}, topic {topic}: {detail}")]
    Endpoint { node: String, topic: String, detail: String },
    #[error("node {node:?}, topic {topic}: carries {expected}, not {requested}")]
    WrongType { node: String, topic: String, expected: String, requested: String },
}

/// How long [`RosNode::flush_before_exit`] waits at most for a stopping node's readers to
/// acknowledge its last messages. A reader that lost the last datagram asks for it only once it
/// has processed the writer's next heartbeat, and a reader on a loaded host can be seconds
/// behind: on the two-host test (2-core machine, load 3) host B's recorder logged the
/// sequencer's states until 2.0 s after the sequencer had exited and never its last one
/// (COMPLETE); a fixed 3 s linger missed it again on CI. Waiting for the acknowledgement ends as
/// soon as every reader has it; only a reader that never answers (killed, its lease not yet
/// run out) costs the whole wait.
pub const FLUSH_DEADLINE: std::time::Duration = std::time::Duration::from_secs(15);

/// A suite node's DDS presence. Create it inside a tokio runtime: the ROS 2 spinner (discovery
/// graph, parameter events) runs as a task on it.
pub struct RosNode {
    node: Node,
    name: String,
    namespace: String,
    domain_id: u16,
    // The context owns the DomainParticipant; keep it alive as long as the node.
    context: Context,
}

impl std::fmt::Debug for RosNode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RosNode")
            .field("name", &self.name)
            .field("namespace", &self.namespace)
            .field("domain_id", &self.domain_id)
            .finish()
    }
}

impl RosNode {
    /// Creates a participant on the configured domain and a node `name` under the namespace;
    /// with `cfg.security`, a secured participant authenticating as the node's enclave.
    pub fn new(name: &str, cfg: &RuntimeConfig) -> Result<Self, RuntimeError> {
        cfg.validate()?;
        let domain_id = cfg.resolved_domain_id()?;
        let mut options = ContextOptions::new().domain_id(domain_id);
        if let Some(sec) = &cfg.security {
            options = crate::security::secure(options, sec, name, &cfg.namespace, domain_id)?;
        }
        let context = Context::with_options(options).map_err(|e| RuntimeError::Participant {
            node: name.to_owned(),
            domain_id,
            detail: format!("{e:?}"),
        })?;
        let node_name = NodeName::new(&cfg.namespace, name)
            .map_err(|e| RuntimeError::Name { node: name.to_owned(), detail: format!("{e:?}") })?;
        let mut node = context
            .new_node(node_name, NodeOptions::new().enable_rosout(false))
            .map_err(|e| RuntimeError::Participant { node: name.to_owned(), domain_id, detail: format!("{e:?}") })?;
        // The spinner serves parameter services and graph events, and subscribes to `/clock`.
        // Secured participants run without it: with RustDDS 0.15.1 a participant may have only
        // one reader per topic matched to a secured writer (the crypto plugin keys the second
        // reader's key material by (remote participant, writer) too, refuses it, and the writer
        // then fails every send), and the spinner's `/clock` reader would be the second one in
        // any node that records `/clock`. The suite's nodes declare no parameters.
        if cfg.security.is_some() {
            tracing::debug!(node = name, "secured participant: no ROS 2 spinner");
        } else {
            match node.spinner() {
                Ok(spinner) => {
                    tokio::spawn(async move {
                        if let Err(e) = spinner.spin().await {
                            tracing::warn!("ROS 2 spinner stopped: {e:?}");
                        }
                    });
                }
                Err(e) => tracing::warn!("node {name}: no ROS 2 spinner ({e:?}); graph events unavailable"),
            }
        }
        let guid = rustdds_guid(&context);
        tracing::debug!(node = name, namespace = %cfg.namespace, domain_id, participant = ?guid.prefix, "node up");
        Ok(Self { node, name: name.to_owned(), namespace: cfg.namespace.clone(), domain_id, context })
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn namespace(&self) -> &str {
        &self.namespace
    }

    pub fn domain_id(&self) -> u16 {
        self.domain_id
    }

    /// Waits until every matched reliable reader of `writers` (this node's publishers' GUIDs)
    /// has acknowledged everything they wrote, for at most [`FLUSH_DEADLINE`]; for a node about
    /// to exit right after its final messages (the sequencer's COMPLETE, the rig's closing count
    /// of its samples). A reliable writer repairs a lost datagram only while its participant
    /// lives, and readers the writer stopped waiting for in flow control (silent for 2 s,
    /// vendor/rustdds PATCHES.md 3) are waited for too (PATCHES.md 4). Returns how many writers
    /// were not acknowledged in time, and logs them.
    pub async fn flush_before_exit(&self, writers: &[(SuiteTopic, ros2_client::dds::rustdds::GUID)]) -> usize {
        let participant = self.context.domain_participant();
        let writers: Vec<_> = writers.iter().map(|(topic, guid)| (self.topic_name(*topic), *guid)).collect();
        let node = self.name.clone();
        let waited = tokio::task::spawn_blocking(move || {
            let deadline = std::time::Instant::now() + FLUSH_DEADLINE;
            let mut unacknowledged = 0;
            for (topic, guid) in writers {
                let left = deadline.saturating_duration_since(std::time::Instant::now());
                match participant.wait_for_acknowledgments(guid, left) {
                    Some(true) => {}
                    Some(false) => {
                        unacknowledged += 1;
                        tracing::warn!(
                            node = %node,
                            "{topic}: not every reader acknowledged the last messages within {} s; exiting anyway",
                            FLUSH_DEADLINE.as_secs()
                        );
                    }
                    None => tracing::warn!(node = %node, "{topic}: no such writer to flush"),
                }
            }
            unacknowledged
        })
        .await;
        waited.unwrap_or_else(|e| {
            tracing::warn!(node = %self.name, "flush before exit failed: {e}");
            0
        })
    }

    /// Full ROS name of a suite topic for this node's namespace.
    pub fn topic_name(&self, topic: SuiteTopic) -> String {
        topic.full_name(&self.namespace)
    }

    /// Checks `M` is the topic's type and returns the topic's full name and parsed ROS name.
    fn checked_name<M: RosMessage>(&self, topic: SuiteTopic) -> Result<(String, Name), RuntimeError> {
        let full = self.topic_name(topic);
        let expected = topic.ros_type_name();
        if expected != M::ros_type_name() {
            return Err(RuntimeError::WrongType {
                node: self.name.clone(),
                topic: full,
                expected,
                requested: M::ros_type_name(),
            });
        }
        let name = Name::parse(&full).map_err(|e| self.endpoint_err(topic, format!("bad topic name: {e:?}")))?;
        Ok((full, name))
    }

    fn endpoint_err(&self, topic: SuiteTopic, detail: String) -> RuntimeError {
        RuntimeError::Endpoint { node: self.name.clone(), topic: self.topic_name(topic), detail }
    }

    /// A typed publisher on a suite topic with the topic's QoS.
    pub fn publisher<M: RosMessage>(&mut self, topic: SuiteTopic) -> Result<Publisher<M>, RuntimeError> {
        let (_, name) = self.checked_name::<M>(topic)?;
        let qos = topic.spec().qos.profile();
        let t = self
            .node
            .create_topic(&name, MessageTypeName::new(M::PACKAGE, M::NAME), &qos)
            .map_err(|e| self.endpoint_err(topic, format!("{e:?}")))?;
        self.node.create_publisher::<M>(&t, Some(qos)).map_err(|e| self.endpoint_err(topic, format!("{e:?}")))
    }

    /// A typed subscription on a suite topic with the topic's QoS.
    pub fn subscription<M: RosMessage + 'static>(
        &mut self,
        topic: SuiteTopic,
    ) -> Result<Subscription<M>, RuntimeError> {
        let (_, name) = self.checked_name::<M>(topic)?;
        let qos = topic.spec().qos.profile();
        let t = self
            .node
            .create_topic(&name, MessageTypeName::new(M::PACKAGE, M::NAME), &qos)
            .map_err(|e| self.endpoint_err(topic, format!("{e:?}")))?;
        self.node.create_subscription::<M>(&t, Some(qos)).map_err(|e| self.endpoint_err(topic, format!("{e:?}")))
    }

    /// A recorder's subscription: the topic's QoS with the deeper reader history of
    /// [`crate::Qos::recording_profile`].
    pub fn recording_subscription<M: RosMessage + 'static>(
        &mut self,
        topic: SuiteTopic,
    ) -> Result<Subscription<M>, RuntimeError> {
        let (_, name) = self.checked_name::<M>(topic)?;
        let qos = topic.spec().qos.recording_profile();
        let t = self
            .node
            .create_topic(&name, MessageTypeName::new(M::PACKAGE, M::NAME), &topic.spec().qos.profile())
            .map_err(|e| self.endpoint_err(topic, format!("{e:?}")))?;
        self.node.create_subscription::<M>(&t, Some(qos)).map_err(|e| self.endpoint_err(topic, format!("{e:?}")))
    }

    /// The underlying ros2-client node (for graph queries in shells).
    pub fn ros_node(&self) -> &Node {
        &self.node
    }

    /// How many subscriptions to a suite topic this participant has discovered (other
    /// participants'; works with and without a spinner).
    pub fn discovered_subscriptions(&self, topic: SuiteTopic) -> usize {
        self.node.subscription_count(&self.topic_name(topic))
    }
}

fn rustdds_guid(context: &Context) -> ros2_client::dds::rustdds::GUID {
    use ros2_client::dds::rustdds::RTPSEntity as _;
    context.domain_participant().guid()
}
