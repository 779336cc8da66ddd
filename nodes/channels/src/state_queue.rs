//! Procedure states waiting for the samples they govern.
//!
//! The sequencer stamps a `ProcedureState` with the rig time of the sample that caused it, so a
//! state stamped `t` governs the samples *after* `t`. Over DDS the two topics arrive in either
//! order, and a log may hold a state and its sample with the same log time in either order; a
//! core that holds each state until a later-stamped sample arrives sees the same sequence in
//! every case. Every core that follows the procedure (channels, monitor) uses this one queue.

use tyre_msgs::ProcedureState;

/// A state stamped further than this ahead of the latest sample is applied at once [s]: a clock
/// mismatch between sequencer and rig must not freeze the phase.
pub const FUTURE_STATE_S: f64 = 1.0;

/// States held until the sample they govern.
#[derive(Debug, Clone, Default)]
pub struct StateQueue {
    pending: Vec<ProcedureState>,
}

impl StateQueue {
    /// Takes a state that arrived when the latest sample was stamped `last_sample_t`. Returns it
    /// when it applies at once (stamped more than [`FUTURE_STATE_S`] ahead); holds it otherwise.
    pub fn offer(&mut self, state: &ProcedureState, last_sample_t: f64) -> Option<ProcedureState> {
        if state.header.stamp.as_secs_f64() > last_sample_t + FUTURE_STATE_S {
            Some(state.clone())
        } else {
            self.pending.push(state.clone());
            None
        }
    }

    /// The held states that govern a sample stamped `t` (stamped before it), in arrival order.
    pub fn due(&mut self, t: f64) -> Vec<ProcedureState> {
        let (due, later) =
            std::mem::take(&mut self.pending).into_iter().partition(|s| s.header.stamp.as_secs_f64() < t);
        self.pending = later;
        due
    }

    /// Every held state, in arrival order (end of the input).
    pub fn drain(&mut self) -> Vec<ProcedureState> {
        std::mem::take(&mut self.pending)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tyre_msgs::std_msgs::Header;

    fn state(t: f64, phase: u8) -> ProcedureState {
        ProcedureState { header: Header::iso_w(t), phase, ..Default::default() }
    }

    #[test]
    fn a_state_waits_for_a_later_sample_and_order_is_kept() {
        let mut q = StateQueue::default();
        assert!(q.offer(&state(1.0, 1), 1.0).is_none());
        assert!(q.offer(&state(1.5, 2), 1.0).is_none());
        assert!(q.offer(&state(1.2, 3), 1.0).is_none());
        assert!(q.due(1.0).is_empty(), "a state stamped t does not govern the sample stamped t");
        assert_eq!(q.due(1.3).iter().map(|s| s.phase).collect::<Vec<_>>(), [1, 3]);
        assert_eq!(q.drain().iter().map(|s| s.phase).collect::<Vec<_>>(), [2]);
        assert!(q.drain().is_empty());
    }

    #[test]
    fn a_state_far_ahead_of_the_samples_applies_at_once() {
        let mut q = StateQueue::default();
        assert_eq!(q.offer(&state(10.0, 4), 8.9).map(|s| s.phase), Some(4));
        assert!(q.offer(&state(9.9, 5), 8.9).is_none());
    }
}
