//! Two nodes, each its own DDS participant, in one process: a RigSample published by one arrives
//! intact at the other; a state topic reaches a late joiner (transient-local).
//!
//! Like every DDS test here it must run in a private network namespace with only loopback up
//! (`scripts/netns-run`): it refuses to run on domain 0 so it cannot disturb a real ROS graph.

use futures::StreamExt;
use node_runtime::{RosNode, RuntimeConfig, SuiteTopic};
use std::time::Duration;
use tyre_msgs::{ProcedureState, RigSample, std_msgs::Header};

fn test_config() -> RuntimeConfig {
    let cfg = RuntimeConfig::default();
    let domain = cfg.resolved_domain_id().expect("ROS_DOMAIN_ID must be a valid domain id");
    assert_ne!(domain, 0, "DDS tests run on a non-zero ROS_DOMAIN_ID inside scripts/netns-run");
    cfg
}

fn sample(seq: u64) -> RigSample {
    RigSample {
        header: Header::iso_w(seq as f64 * 0.01),
        seq,
        runtime_s: seq as f64 * 0.01,
        fx_n: 100.5 + seq as f64,
        fyw_n: -6320.515,
        fzw_n: 6752.0,
        slipangl_deg: 4.0,
        trdtempc_c: 45.0,
        ..Default::default()
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sample_crosses_between_two_participants() -> anyhow::Result<()> {
    let cfg = test_config();
    let mut rig = RosNode::new("test_rig", &cfg)?;
    let mut listener = RosNode::new("test_listener", &cfg)?;
    let publisher = rig.publisher::<RigSample>(SuiteTopic::RigSample)?;
    let subscription = listener.subscription::<RigSample>(SuiteTopic::RigSample)?;

    // Discovery over loopback takes a moment; publish until the first sample arrives, then a
    // numbered burst that must arrive complete and in order (reliable QoS).
    let mut stream = Box::pin(subscription.async_stream());
    let first = tokio::time::timeout(Duration::from_secs(20), async {
        loop {
            publisher.publish(sample(0)).map_err(|e| anyhow::anyhow!("{e:?}"))?;
            if let Ok(Some(msg)) = tokio::time::timeout(Duration::from_millis(200), stream.next()).await {
                return anyhow::Ok(msg.map_err(|e| anyhow::anyhow!("{e:?}"))?.0);
            }
        }
    })
    .await??;
    assert_eq!(first, sample(0));

    for seq in 1..=200 {
        publisher.publish(sample(seq)).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    }
    let mut next = 1;
    while next <= 200 {
        let (msg, _) = tokio::time::timeout(Duration::from_secs(10), stream.next())
            .await?
            .ok_or_else(|| anyhow::anyhow!("stream ended"))?
            .map_err(|e| anyhow::anyhow!("{e:?}"))?;
        if msg.seq == 0 {
            continue; // extra copies of the discovery probe
        }
        assert_eq!(msg, sample(next));
        next += 1;
    }
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn state_reaches_a_late_joiner() -> anyhow::Result<()> {
    let cfg = test_config();
    let mut sequencer = RosNode::new("test_sequencer", &cfg)?;
    let publisher = sequencer.publisher::<ProcedureState>(SuiteTopic::ProcedureState)?;
    let state = ProcedureState {
        procedure: "gs2mf_freerolling".into(),
        sweep_name: "FreeRoll_sw14_VariableRate_LR2_HR30_TH4_1".into(),
        phase: ProcedureState::PHASE_THERMAL_PAUSE,
        ..Default::default()
    };
    publisher.publish(state.clone()).map_err(|e| anyhow::anyhow!("{e:?}"))?;

    // The control room joins after the state was published.
    tokio::time::sleep(Duration::from_millis(300)).await;
    let mut control_room = RosNode::new("test_control_room", &cfg)?;
    let subscription = control_room.subscription::<ProcedureState>(SuiteTopic::ProcedureState)?;
    let (got, _) = tokio::time::timeout(Duration::from_secs(20), subscription.async_take())
        .await?
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    assert_eq!(got, state);
    Ok(())
}

#[test]
fn a_topic_refuses_the_wrong_type() {
    let rt = tokio::runtime::Runtime::new().expect("tokio runtime");
    rt.block_on(async {
        let cfg = test_config();
        let mut node = RosNode::new("test_typecheck", &cfg).expect("node");
        let Err(err) = node.publisher::<ProcedureState>(SuiteTopic::RigSample) else {
            panic!("a ProcedureState publisher on the RigSample topic must be refused");
        };
        assert!(err.to_string().contains("tyre_msgs/msg/RigSample"), "{err}");
    });
}
