//! recorder: the recorder node (every suite topic → one MCAP log) and replay (a log → its topics).
//!
//! The MCAP writing, reading and recovery are in the DDS-free [`mcaplog`] crate; this crate adds
//! the DDS side.
//!
//! - [`shell`]: the recorder node. Topics: subscribes to every [`node_runtime::SuiteTopic`] (or the
//!   configured subset). `log_time` = receive time (system clock, ns since the UNIX epoch);
//!   `publish_time` = the message's `header.stamp` (rig time).
//! - [`replay`]: republishes a log onto the same topics with its original timing, scaled.

pub mod config;
pub mod forward;
pub mod replay;
pub mod shell;

pub use config::RecorderConfig;
pub use mcaplog::{LogError, LogMessage, LogReader, McapLog, McapLogOptions, codec, recover};

#[cfg(test)]
mod tests {
    use mcaplog::codec::{decode, encode, leading_stamp};
    use node_runtime::{SuiteTopic, topics::TopicVisitor};
    use tyre_msgs::{RosMessage, builtin_interfaces::Time};

    #[test]
    fn every_suite_topic_starts_with_its_stamp() {
        // The recorder's publish_time relies on it: the first 8 body bytes are the stamp.
        struct Check;
        impl TopicVisitor for Check {
            type Output = ();
            fn visit<M: RosMessage + Send + Sync + 'static>(self, topic: SuiteTopic) {
                let probe = Time { sec: 1_234_567, nanosec: 890_123_456 };
                // Encode a default message, patch the stamp bytes, and decode: a type whose first
                // field is not a stamp would decode to a different value or fail.
                let default: M =
                    decode(&encode(&default_of::<M>(), "probe").expect("encode"), "probe").expect("decode");
                let mut bytes = encode(&default, "probe").expect("encode");
                bytes[4..8].copy_from_slice(&probe.sec.to_le_bytes());
                bytes[8..12].copy_from_slice(&probe.nanosec.to_le_bytes());
                let patched: M = decode(&bytes, "probe").unwrap_or_else(|e| panic!("{topic:?}: {e}"));
                let re = encode(&patched, "probe").expect("encode");
                assert_eq!(leading_stamp(&re), Some(probe), "{topic:?}");
            }
        }
        fn default_of<M: RosMessage>() -> M {
            tyre_msgs::introspect::exemplar::<M>(2).expect("exemplar")
        }
        for t in SuiteTopic::ALL {
            t.visit(Check);
        }
    }
}
