//! What a client that subscribes late is sent first: the last message(s) of each latched
//! channel, as DDS transient-local durability does for the suite's state and event topics. The
//! Foxglove protocol has no durability of its own, so without this a browser opened mid-run
//! would show no plan, no procedure state and no alarms until they next change.

use std::collections::{BTreeMap, VecDeque};

/// Bounded per-channel history of encoded messages, keyed by `K`.
#[derive(Debug, Clone)]
pub struct Latch<K: Ord> {
    depth: BTreeMap<K, usize>,
    kept: BTreeMap<K, VecDeque<(u64, Vec<u8>)>>,
}

impl<K: Ord + Copy> Latch<K> {
    /// `depth`: how many messages each latched channel keeps (channels not listed keep none).
    pub fn new(depth: impl IntoIterator<Item = (K, usize)>) -> Self {
        Self { depth: depth.into_iter().filter(|(_, d)| *d > 0).collect(), kept: BTreeMap::new() }
    }

    pub fn is_latched(&self, key: K) -> bool {
        self.depth.contains_key(&key)
    }

    /// Keeps `payload` (logged at `log_time_ns`) if the channel is latched.
    pub fn keep(&mut self, key: K, log_time_ns: u64, payload: &[u8]) {
        let Some(&depth) = self.depth.get(&key) else { return };
        let q = self.kept.entry(key).or_default();
        if q.len() == depth {
            q.pop_front();
        }
        q.push_back((log_time_ns, payload.to_vec()));
    }

    /// The kept messages of a channel, oldest first.
    pub fn replay(&self, key: K) -> Vec<(u64, Vec<u8>)> {
        self.kept.get(&key).map(|q| q.iter().cloned().collect()).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_the_last_n_of_latched_channels_only() {
        let mut l = Latch::new([(1, 1), (2, 3), (3, 0)]);
        for i in 0..5u8 {
            for k in [1, 2, 3, 4] {
                l.keep(k, u64::from(i), &[i]);
            }
        }
        assert_eq!(l.replay(1), vec![(4, vec![4])]);
        assert_eq!(l.replay(2), vec![(2, vec![2]), (3, vec![3]), (4, vec![4])]);
        assert!(l.replay(3).is_empty() && l.replay(4).is_empty());
        assert!(l.is_latched(2) && !l.is_latched(3));
    }
}
