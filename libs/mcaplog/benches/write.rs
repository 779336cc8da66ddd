//! Log writing throughput: `McapLog` (ROS 2 profile, zstd chunks closed every second of log
//! time, message indexes, summary) against the raw `mcap` writer with the same options, on the
//! same encoded `RigSample`s (10,000 per iteration = 10 s at 1 kHz).
//!
//! `cargo bench -p mcaplog --bench write`

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mcaplog::{McapLog, McapLogOptions, codec};
use std::{collections::BTreeMap, hint::black_box};
use tyre_msgs::{RigSample, RosMessage, std_msgs::Header};

const N: u64 = 10_000;

fn messages() -> Vec<Vec<u8>> {
    (0..N)
        .map(|i| {
            let s = RigSample {
                header: Header::iso_w(i as f64 * 1e-3),
                seq: i,
                runtime_s: i as f64 * 1e-3,
                fx_n: (i as f64 * 0.01).sin() * 5000.0,
                fyw_n: (i as f64 * 0.013).cos() * 6000.0,
                fzw_n: 6752.0 + (i % 7) as f64,
                trdtempc_c: 45.0 + (i % 100) as f64 * 0.1,
                ..Default::default()
            };
            codec::encode(&s, "RigSample").expect("encode")
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let msgs = messages();
    let bytes: u64 = msgs.iter().map(|m| m.len() as u64).sum();
    let schema = tyre_msgs::schema::ros2msg_schema::<RigSample>().expect("schema");
    let dir = tempfile::tempdir().expect("tempdir");
    let mut g = c.benchmark_group("write_10k_rig_samples");
    g.throughput(Throughput::Elements(N));
    g.bench_function("mcaplog::McapLog", |b| {
        b.iter(|| {
            let path = dir.path().join("ours.mcap");
            let mut log = McapLog::create(&path, McapLogOptions::default()).expect("create");
            let ch = log.ensure_channel("/rig/sample", &RigSample::ros_type_name(), &schema).expect("channel");
            for (i, m) in msgs.iter().enumerate() {
                let t = i as u64 * 1_000_000;
                log.write(ch, t, t, m).expect("write");
            }
            black_box(log.finish().expect("finish"))
        })
    });
    g.bench_function("mcap::Writer (raw)", |b| {
        b.iter(|| {
            let path = dir.path().join("raw.mcap");
            let file = std::io::BufWriter::new(std::fs::File::create(&path).expect("create"));
            let mut w = mcap::WriteOptions::new()
                .profile("ros2")
                .compression(Some(mcap::Compression::Zstd))
                .compression_level(3)
                .chunk_size(Some(1 << 20))
                .create(file)
                .expect("writer");
            let sid = w.add_schema("tyre_msgs/msg/RigSample", "ros2msg", schema.as_bytes()).expect("schema");
            let ch = w.add_channel(sid, "/rig/sample", "cdr", &BTreeMap::new()).expect("channel");
            for (i, m) in msgs.iter().enumerate() {
                let t = i as u64 * 1_000_000;
                let h =
                    mcap::records::MessageHeader { channel_id: ch, sequence: i as u32, log_time: t, publish_time: t };
                w.write_to_known_channel(&h, m).expect("write");
            }
            black_box(w.finish().expect("finish"))
        })
    });
    g.finish();
    println!("payload per iteration: {bytes} bytes ({:.1} bytes/message)", bytes as f64 / N as f64);
}

criterion_group!(benches, bench);
criterion_main!(benches);
