//! Reader speed on a 20,000-row TTC-like run (the size of a real run): parsing alone, and the
//! whole import (interpretation, sweep finding, samples), for `.dat` and `.mat`.
//!
//! `cargo bench -p rigdata --bench readers` (criterion prints time and rows/s).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rigdata::fixture::{FixtureSpec, ttc_run};
use rigdata::import::{FileFormat, ReadOptions, read_bytes};
use rigdata::mat::{MatWriteOptions, to_mat};
use rigdata::table::{DatLayout, to_dat};

const ROWS: usize = 20_000;

fn run_table() -> rigdata::ChannelTable {
    let spec = FixtureSpec {
        pressures_kpa: vec![70.0, 84.0, 98.0, 112.0],
        loads_n: vec![1100.0, 1540.0, 660.0, 220.0],
        ..FixtureSpec::cornering()
    };
    let mut t = ttc_run(&spec).table;
    assert!(t.rows() >= ROWS, "fixture has {} rows", t.rows());
    for c in &mut t.columns {
        c.values.truncate(ROWS);
    }
    t
}

fn readers(c: &mut Criterion) {
    let t = run_table();
    let dat = to_dat(&t, DatLayout::default()).into_bytes();
    let mat = to_mat(&t, &MatWriteOptions::default()).unwrap();
    let mat_raw = to_mat(&t, &MatWriteOptions { compress: false, ..Default::default() }).unwrap();
    let opt = ReadOptions::default();
    let mut g = c.benchmark_group("readers_20k_rows");
    g.throughput(Throughput::Elements(ROWS as u64));
    g.sample_size(20);
    g.bench_function("dat_parse", |b| b.iter(|| rigdata::dat::parse_dat(&dat, "run.dat").unwrap()));
    g.bench_function("mat_parse_compressed", |b| b.iter(|| rigdata::mat::parse_mat(&mat, "run.mat").unwrap()));
    g.bench_function("mat_parse_uncompressed", |b| b.iter(|| rigdata::mat::parse_mat(&mat_raw, "run.mat").unwrap()));
    g.bench_function("dat_import", |b| b.iter(|| read_bytes(&dat, "run.dat", FileFormat::Dat, &opt).unwrap()));
    g.bench_function("mat_import", |b| b.iter(|| read_bytes(&mat, "run.mat", FileFormat::Mat, &opt).unwrap()));
    g.finish();
}

criterion_group!(benches, readers);
criterion_main!(benches);
