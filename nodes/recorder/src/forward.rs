//! One subscription's messages to the writer thread, with an orderly stop that keeps what the
//! reader already holds.
//!
//! A stop must not drop what DDS has already delivered: under load the recorder's readers run
//! behind the publishers (their history is deep so that they can), and at the stop the messages
//! waiting in a reader are part of the run. `tyrerig run` lost the last 904 RigSamples of a
//! StaticLong run this way on a loaded 2-core machine while the quality node had them all.
//! So after the stop the task goes on taking until its reader has been quiet for
//! [`DRAIN_QUIET`], for at most [`DRAIN_LIMIT`] (a live rig that keeps publishing would
//! otherwise hold the stop open for ever).

use futures::{Stream, StreamExt};
use node_runtime::Shutdown;
use std::time::Duration;
use tokio::sync::mpsc;

/// After the stop, a reader that delivers nothing for this long has been emptied.
pub const DRAIN_QUIET: Duration = Duration::from_millis(200);
/// After the stop, take for at most this long.
pub const DRAIN_LIMIT: Duration = Duration::from_secs(2);

/// How a subscription's forwarding ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Forwarded {
    /// Items taken after the stop (the reader's backlog).
    pub drained: u64,
    /// The drain ended on [`DRAIN_LIMIT`] with items still arriving.
    pub drain_cut_short: bool,
}

/// Takes `stream` until `shutdown`, then drains it (see the module), sending what `convert`
/// makes of each item to `tx`. Ends early when the stream ends or the receiver is gone.
pub async fn forward<I, O>(
    stream: impl Stream<Item = I>,
    shutdown: &Shutdown,
    tx: &mpsc::Sender<O>,
    mut convert: impl FnMut(I) -> Option<O>,
) -> Forwarded {
    let mut stream = std::pin::pin!(stream);
    let mut done = Forwarded { drained: 0, drain_cut_short: false };
    loop {
        let item = tokio::select! {
            // The stop first: after it, every item counts as drained.
            biased;
            _ = shutdown.wait() => break,
            item = stream.next() => item,
        };
        let Some(item) = item else { return done };
        if let Some(out) = convert(item)
            && tx.send(out).await.is_err()
        {
            return done;
        }
    }
    let started = tokio::time::Instant::now();
    while let Ok(Some(item)) = tokio::time::timeout(DRAIN_QUIET, stream.next()).await {
        done.drained += 1;
        if let Some(out) = convert(item)
            && tx.send(out).await.is_err()
        {
            return done;
        }
        if started.elapsed() >= DRAIN_LIMIT {
            done.drain_cut_short = true;
            break;
        }
    }
    done
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn a_stop_keeps_what_the_reader_already_holds() {
        // The stop comes before the task takes anything: every held item must still arrive.
        let shutdown = Shutdown::new();
        shutdown.trigger();
        let (tx, mut rx) = mpsc::channel(2000);
        let held = futures::stream::iter(0..1000u32).chain(futures::stream::pending());
        let done = forward(held, &shutdown, &tx, Some).await;
        drop(tx);
        let mut got = Vec::new();
        while let Some(v) = rx.recv().await {
            got.push(v);
        }
        assert_eq!(got, (0..1000).collect::<Vec<_>>());
        assert_eq!(done, Forwarded { drained: 1000, drain_cut_short: false });
    }

    #[tokio::test(start_paused = true)]
    async fn a_stream_that_keeps_flowing_is_cut_at_the_limit() {
        let shutdown = Shutdown::new();
        shutdown.trigger();
        let (tx, mut rx) = mpsc::channel(100_000);
        // One item every 10 ms, for ever: a live rig still publishing.
        let live = futures::stream::unfold(0u64, |n| async move {
            tokio::time::sleep(Duration::from_millis(10)).await;
            Some((n, n + 1))
        });
        let done = forward(live, &shutdown, &tx, Some).await;
        assert!(done.drain_cut_short);
        // 2 s of 10 ms items, give or take the last one.
        assert!((200..=201).contains(&done.drained), "{done:?}");
        drop(tx);
        let mut n = 0;
        while rx.recv().await.is_some() {
            n += 1;
        }
        assert_eq!(n, done.drained);
    }

    #[tokio::test]
    async fn items_before_the_stop_flow_and_the_end_of_the_stream_ends_it() {
        let shutdown = Shutdown::new();
        let (tx, mut rx) = mpsc::channel(10);
        // Odd items do not convert (a message that fails to encode): they are skipped, not sent.
        let done = forward(futures::stream::iter(0..6u32), &shutdown, &tx, |v| (v % 2 == 0).then_some(v)).await;
        drop(tx);
        let mut got = Vec::new();
        while let Some(v) = rx.recv().await {
            got.push(v);
        }
        assert_eq!(got, vec![0, 2, 4]);
        assert_eq!(done, Forwarded { drained: 0, drain_cut_short: false });
    }
}
