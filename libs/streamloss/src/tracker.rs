//! [`SeqTracker`]: one writer's sequence numbers as one reader saw them.

/// A run of sequence numbers that never arrived, `first..=last`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Gap {
    pub first: u64,
    pub last: u64,
}

impl Gap {
    /// How many messages the gap holds (saturates at `u64::MAX`).
    pub fn len(&self) -> u64 {
        (self.last - self.first).saturating_add(1)
    }

    /// A gap always holds at least one message.
    pub fn is_empty(&self) -> bool {
        false
    }
}

impl std::fmt::Display for Gap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.first == self.last { write!(f, "{}", self.first) } else { write!(f, "{}-{}", self.first, self.last) }
    }
}

/// What one received sequence number meant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Observation {
    /// The writer's first message this reader saw.
    First,
    /// The next one expected.
    InOrder,
    /// Messages were skipped: the gap is what is missing before this one.
    Gap(Gap),
    /// At or below one already seen: a duplicate or a straggler (not counted as received).
    Late,
}

/// Gap ranges kept per tracker; further gaps are counted but their ranges are not kept, so a
/// hostile or broken writer cannot make a reader's memory grow.
pub const MAX_GAP_RANGES: usize = 100;

/// One writer's sequence as seen by one reader.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SeqTracker {
    first: Option<u64>,
    last: u64,
    received: u64,
    lost: u64,
    late: u64,
    gaps: Vec<Gap>,
    gaps_total: u64,
    /// The highest sequence number the writer says it made (its own count, e.g. the rig's
    /// announced `RigSample.seq`), see [`SeqTracker::claim`].
    claimed: Option<u64>,
}

impl SeqTracker {
    pub fn new() -> Self {
        Self::default()
    }

    /// Records sequence number `seq` and says what it meant.
    pub fn observe(&mut self, seq: u64) -> Observation {
        let Some(_) = self.first else {
            self.first = Some(seq);
            self.last = seq;
            self.received = 1;
            return Observation::First;
        };
        if seq <= self.last {
            self.late = self.late.saturating_add(1);
            return Observation::Late;
        }
        self.received = self.received.saturating_add(1);
        let expected = self.last + 1;
        self.last = seq;
        if seq == expected {
            return Observation::InOrder;
        }
        let gap = Gap { first: expected, last: seq - 1 };
        self.lost = self.lost.saturating_add(gap.len());
        self.gaps_total = self.gaps_total.saturating_add(1);
        if self.gaps.len() < MAX_GAP_RANGES {
            self.gaps.push(gap);
        }
        Observation::Gap(gap)
    }

    /// The writer says it made every sequence number up to `upto` (its own count, announced
    /// beside the stream). What it made after the last one received and never arrived is the
    /// stream's tail ([`SeqTracker::tail`]): a stream that stops early leaves no gap, since no
    /// later message comes to show one. Claims before the first message seen are ignored (a
    /// late-joining reader was not owed them); a lower claim than an earlier one changes nothing.
    pub fn claim(&mut self, upto: u64) {
        if self.first.is_some() {
            self.claimed = Some(self.claimed.map_or(upto, |c| c.max(upto)));
        }
    }

    /// Messages the writer says it made after the last one received ([`SeqTracker::claim`]);
    /// 0 once a later message arrives (what is missing before it is then a gap).
    pub fn tail(&self) -> u64 {
        match (self.first, self.claimed) {
            (Some(_), Some(c)) if c > self.last => c - self.last,
            _ => 0,
        }
    }

    /// The writer's highest claim, if any.
    pub fn claimed(&self) -> Option<u64> {
        self.claimed
    }

    /// First sequence number seen, if any.
    pub fn first_seq(&self) -> Option<u64> {
        self.first
    }

    /// Highest sequence number seen, if any.
    pub fn last_seq(&self) -> Option<u64> {
        self.first.map(|_| self.last)
    }

    /// Distinct messages received in order (late copies excluded).
    pub fn received(&self) -> u64 {
        self.received
    }

    /// Messages missing between the first and the last one seen.
    pub fn lost(&self) -> u64 {
        self.lost
    }

    /// Duplicates and stragglers.
    pub fn late(&self) -> u64 {
        self.late
    }

    /// The first [`MAX_GAP_RANGES`] gaps.
    pub fn gaps(&self) -> &[Gap] {
        &self.gaps
    }

    /// Every gap, kept or not.
    pub fn gaps_total(&self) -> u64 {
        self.gaps_total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn in_order_stream_has_no_loss() {
        let mut t = SeqTracker::new();
        assert_eq!(t.observe(5), Observation::First);
        for s in 6..100 {
            assert_eq!(t.observe(s), Observation::InOrder);
        }
        assert_eq!((t.received(), t.lost(), t.gaps_total()), (95, 0, 0));
        assert_eq!((t.first_seq(), t.last_seq()), (Some(5), Some(99)));
    }

    #[test]
    fn gaps_are_ranges_and_counts() {
        let mut t = SeqTracker::new();
        t.observe(1);
        t.observe(2);
        assert_eq!(t.observe(6), Observation::Gap(Gap { first: 3, last: 5 }));
        assert_eq!(t.observe(8), Observation::Gap(Gap { first: 7, last: 7 }));
        assert_eq!(t.observe(4), Observation::Late);
        assert_eq!(t.observe(8), Observation::Late);
        assert_eq!((t.received(), t.lost(), t.late()), (4, 4, 2));
        assert_eq!(t.gaps().iter().map(ToString::to_string).collect::<Vec<_>>(), ["3-5", "7"]);
    }

    #[test]
    fn ranges_are_bounded_but_counts_are_not() {
        let mut t = SeqTracker::new();
        for i in 0..1000u64 {
            t.observe(i * 2);
        }
        assert_eq!(t.gaps().len(), MAX_GAP_RANGES);
        assert_eq!(t.gaps_total(), 999);
        assert_eq!(t.lost(), 999);
    }

    #[test]
    fn a_claim_beyond_the_last_message_is_a_tail_until_later_ones_come() {
        let mut t = SeqTracker::new();
        t.claim(50); // before the first message: not owed to this reader
        assert_eq!((t.tail(), t.claimed()), (0, None));
        for s in 10..=20 {
            t.observe(s);
        }
        t.claim(20);
        assert_eq!(t.tail(), 0, "everything claimed arrived");
        t.claim(35);
        t.claim(30); // an older announcement arriving late lowers nothing
        assert_eq!((t.tail(), t.claimed()), (15, Some(35)));
        // The stream comes back after a jump: the tail becomes a gap, never counted twice.
        t.observe(40);
        assert_eq!((t.tail(), t.lost()), (0, 19));
    }

    #[test]
    fn a_huge_jump_saturates_instead_of_overflowing() {
        let mut t = SeqTracker::new();
        t.observe(0);
        t.observe(u64::MAX);
        assert_eq!(t.lost(), u64::MAX - 1);
        t.observe(1);
        assert_eq!(t.late(), 1);
    }
}
