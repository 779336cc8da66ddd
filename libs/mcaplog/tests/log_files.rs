//! The log writer, reader and recovery on real files (no DDS).

use mcaplog::{
    LogReader, McapLog, McapLogOptions, codec,
    recover::{RecoverError, recover},
};
use std::collections::BTreeMap;
use tyre_msgs::{RigSample, RosMessage, std_msgs::Header};

fn sample(seq: u64) -> RigSample {
    RigSample {
        header: Header::iso_w(seq as f64 * 1e-3),
        seq,
        runtime_s: seq as f64 * 1e-3,
        fyw_n: -6000.0 + seq as f64,
        trdtempc_c: 45.0 + (seq % 100) as f64 * 0.1,
        ..Default::default()
    }
}

/// Writes `n` samples at 1 kHz log time with chunks closed every `flush_s` of log time.
fn write_log(path: &std::path::Path, n: u64, flush_s: f64, finish: bool) -> anyhow::Result<()> {
    let mut log = McapLog::create(path, McapLogOptions { flush_interval_s: flush_s, ..Default::default() })?;
    let mut md = BTreeMap::new();
    md.insert("file".to_owned(), "MagicFormula61_Paramerters.tir".to_owned());
    log.write_metadata("tyre", &md)?;
    let schema = tyre_msgs::schema::ros2msg_schema::<RigSample>()?;
    let ch = log.ensure_channel("/rig/sample", &RigSample::ros_type_name(), &schema)?;
    for seq in 0..n {
        let data = codec::encode(&sample(seq), "RigSample")?;
        let t = 1_000_000_000 + seq * 1_000_000;
        log.write(ch, t, codec::leading_stamp(&data).map_or(0, |s| s.as_nanos()), &data)?;
    }
    if finish {
        log.finish()?;
    } else {
        log.flush()?;
        // Simulate a crash: forget the writer without writing the summary.
        std::mem::forget(log);
    }
    Ok(())
}

#[test]
fn written_log_reads_back_exactly() -> anyhow::Result<()> {
    let dir = tempfile::tempdir()?;
    let path = dir.path().join("run.mcap");
    write_log(&path, 2500, 1.0, true)?;
    let log = LogReader::open(&path)?;
    let got = log.typed::<RigSample>("/rig/sample")?;
    assert_eq!(got.len(), 2500);
    for (i, (t, m)) in got.iter().enumerate() {
        assert_eq!(*m, sample(i as u64));
        assert_eq!(*t, 1_000_000_000 + i as u64 * 1_000_000);
    }
    assert_eq!(log.metadata()["tyre"]["file"], "MagicFormula61_Paramerters.tir");
    let topics = log.topics();
    assert_eq!(topics.len(), 1);
    assert_eq!(topics[0].ros_type, "tyre_msgs/msg/RigSample");
    // publish_time is the message's stamp
    let first = &log.messages()[1];
    assert_eq!(first.publish_time_ns, 1_000_000);
    Ok(())
}

#[test]
fn wrong_type_request_is_named() -> anyhow::Result<()> {
    let dir = tempfile::tempdir()?;
    let path = dir.path().join("run.mcap");
    write_log(&path, 10, 1.0, true)?;
    let log = LogReader::open(&path)?;
    let err = log.typed::<tyre_msgs::ProcedureState>("/rig/sample").expect_err("wrong type");
    let text = err.to_string();
    assert!(text.contains("run.mcap") && text.contains("/rig/sample") && text.contains("RigSample"), "{text}");
    Ok(())
}

#[test]
fn not_an_mcap_file_is_named() -> anyhow::Result<()> {
    let dir = tempfile::tempdir()?;
    let path = dir.path().join("notes.mcap");
    std::fs::write(&path, "this is not a log\n")?;
    let err = LogReader::open(&path).expect_err("not mcap");
    assert!(err.to_string().contains("notes.mcap"), "{err}");
    let out = dir.path().join("out.mcap");
    assert!(matches!(recover(&path, &out), Err(RecoverError::NotMcap { .. })));
    Ok(())
}

/// Cuts a crashed log at many byte offsets. Recovery must always give a valid file holding
/// exactly the messages of the chunks that were complete before the cut, in order.
#[test]
fn recovery_keeps_every_complete_chunk_at_any_cut() -> anyhow::Result<()> {
    let dir = tempfile::tempdir()?;
    let path = dir.path().join("crashed.mcap");
    // 0.25 s chunks at 1 kHz: about 250 messages per chunk.
    write_log(&path, 3000, 0.25, false)?;
    let full = std::fs::read(&path)?;

    // Where each chunk ends, found independently of the recovery code by walking the records.
    let mut chunk_ends = Vec::new(); // (end offset, messages so far)
    let mut pos = 8usize; // after the magic
    let mut msgs_so_far = 0u64;
    while pos + 9 <= full.len() {
        let op = full[pos];
        let len = u64::from_le_bytes(full[pos + 1..pos + 9].try_into()?) as usize;
        let end = pos + 9 + len;
        if end > full.len() {
            break;
        }
        if op == 0x06 {
            // Chunk record: message_start_time u64, message_end_time u64, ... Messages are 1 ms
            // apart, so the chunk holds (end - start) / 1 ms + 1 of them.
            let start = u64::from_le_bytes(full[pos + 9..pos + 17].try_into()?);
            let stop = u64::from_le_bytes(full[pos + 17..pos + 25].try_into()?);
            msgs_so_far += (stop - start) / 1_000_000 + 1;
            chunk_ends.push((end, msgs_so_far));
        }
        pos = end;
    }
    assert!(chunk_ends.len() >= 10, "expected about 12 chunks, found {}", chunk_ends.len());
    assert_eq!(chunk_ends.last().map(|c| c.1), Some(3000), "the chunks hold every message");

    let cuts: Vec<usize> = (0..40).map(|i| 8 + i * (full.len() - 8) / 40).chain([full.len()]).collect();
    for cut in cuts {
        let cut_path = dir.path().join("cut.mcap");
        std::fs::write(&cut_path, &full[..cut])?;
        let out = dir.path().join("recovered.mcap");
        let report = recover(&cut_path, &out)?;
        let expected = chunk_ends.iter().filter(|(end, _)| *end <= cut).map(|(_, n)| *n).max().unwrap_or(0);
        assert_eq!(report.messages, expected, "cut at {cut} of {}", full.len());
        let log = LogReader::open(&out)?;
        let got = log.typed::<RigSample>("/rig/sample")?;
        assert_eq!(got.len() as u64, expected);
        for (i, (_, m)) in got.iter().enumerate() {
            assert_eq!(*m, sample(i as u64));
        }
        if cut > 200 {
            assert_eq!(log.metadata()["tyre"]["file"], "MagicFormula61_Paramerters.tir", "metadata kept at cut {cut}");
        }
    }
    Ok(())
}

#[test]
fn a_crashed_log_is_reported_as_truncated_with_the_fix() -> anyhow::Result<()> {
    let dir = tempfile::tempdir()?;
    let path = dir.path().join("crashed.mcap");
    write_log(&path, 600, 0.25, false)?;
    let full = std::fs::read(&path)?;
    std::fs::write(&path, &full[..full.len() - 100])?;
    let err = LogReader::open(&path).expect_err("truncated");
    assert!(err.to_string().contains("tyrerig mcap recover"), "{err}");
    Ok(())
}
