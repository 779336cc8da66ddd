//! Every parser of user input, fuzzed with a fixed case budget (see `parser_fuzz`). One line per
//! parser: the name, the seeds (real files of that kind), the budget, the call.
//!
//! Budgets are per parser and fixed, so CI time is bounded and repeatable; `FUZZ_CASES=N`
//! overrides them all for a longer local run.

use parser_fuzz::{fuzz, text};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn read(rel: &str) -> Vec<u8> {
    std::fs::read(repo().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Cases per parser in CI: 2,000 each, about 10 s for all of them on two cores.
const BUDGET: u32 = 2000;

/// The budget, unless `FUZZ_CASES` says otherwise.
fn cases(default: u32) -> u32 {
    std::env::var("FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

fn err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

#[test]
fn tir_files() {
    let seeds = ["MagicFormula61_Parameters.tir", "FSAE_Defaults.tir", "PacejkaBook_Defaults.tir"]
        .map(|f| read(&format!("launch-config/tyres/{f}")))
        .to_vec();
    fuzz("tir", seeds, cases(BUDGET), |b| {
        let p = mftyre::TyreParams::from_tir_str(&text(b), "fuzz.tir").map_err(err)?;
        p.validate().map_err(err)
    });
}

#[test]
fn procedure_files() {
    let dir = repo().join("launch-config/procedures");
    let names = ["gs2mf_freerolling.toml", "gs2mf_brkdrv.toml", "gs2mf_staticlong.toml", "square_matrix.toml"];
    let seeds = names.map(|f| read(&format!("launch-config/procedures/{f}"))).to_vec();
    fuzz("procedure TOML (parse + expand)", seeds, cases(BUDGET), |b| {
        // Includes resolve to the shipped files; the fuzzed file is the one being parsed.
        let mut include = |p: &str| {
            let name = Path::new(p).file_name().map(|n| dir.join(n)).unwrap_or_default();
            std::fs::read_to_string(&name)
                .map_err(|source| procedure::ProcedureError::Read { file: p.to_owned(), source })
        };
        let doc = procedure::parse_with("fuzz.toml", &text(b), &mut include).map_err(err)?;
        let plan = procedure::expand(&doc, &procedure::RunInputs::default()).map_err(err)?;
        let _ = plan.estimate_total_s(&procedure::PauseModel::default());
        Ok(())
    });
}

#[test]
fn node_config_tables() {
    // The typed `[node.config]` tables of a launch file and the config files they point to.
    let thermal = toml::to_string(&thermal::ThermalConfig::default()).expect("thermal toml");
    let seq = toml::to_string(&sequencer::SequencerConfig::default()).expect("sequencer toml");
    let chan = toml::to_string(&channels::ChannelsConfig::default()).expect("channels toml");
    let mon = toml::to_string(&monitor::MonitorConfig::default()).expect("monitor toml");
    let quality = toml::to_string(&monitor::shell::QualityNodeConfig::default()).expect("quality toml");
    fuzz("thermal config TOML", vec![thermal.into_bytes()], cases(BUDGET), |b| {
        thermal::ThermalConfig::from_toml_str(&text(b)).map(|_| ()).map_err(err)
    });
    fuzz("sequencer config TOML", vec![seq.into_bytes()], cases(BUDGET), |b| {
        sequencer::SequencerConfig::from_toml(&text(b)).map(|_| ()).map_err(err)
    });
    fuzz("channels config TOML", vec![chan.into_bytes()], cases(BUDGET), |b| {
        channels::ChannelsConfig::from_toml(&text(b)).map(|_| ()).map_err(err)
    });
    fuzz("monitor config TOML", vec![mon.into_bytes()], cases(BUDGET), |b| {
        monitor::MonitorConfig::from_toml(&text(b)).map(|_| ()).map_err(err)
    });
    fuzz("quality node config TOML", vec![quality.into_bytes()], cases(BUDGET), |b| {
        let c: monitor::shell::QualityNodeConfig = toml::from_str(&text(b)).map_err(err)?;
        c.validate().map_err(err)
    });
    fuzz("recorder config TOML", vec![b"output = \"out/run.mcap\"\ntopics = [\"sample\"]\nflush_interval_s = 0.5\nzstd_level = 3\nchunk_size_bytes = 4096\non_existing = \"new_file\"\n[metadata.tyre]\nname = \"x\"\n".to_vec()], cases(BUDGET), |b| {
        let c: recorder::RecorderConfig = toml::from_str(&text(b)).map_err(err)?;
        c.validate().map_err(err)?;
        recorder::shell::selected_topics(&c, "/rig").map(|_| ()).map_err(err)
    });
    fuzz("runtime config TOML", vec![b"namespace = \"/rig\"\ndomain_id = 42\n".to_vec()], cases(BUDGET), |b| {
        let c: node_runtime::RuntimeConfig = toml::from_str(&text(b)).map_err(err)?;
        c.validate().map_err(err)
    });
}

#[test]
fn virtual_rig_config() {
    fuzz("virtual rig config TOML", vec![read("launch-config/virtual_rig.toml")], cases(BUDGET), |b| {
        rigsim::RigConfig::from_toml_str(&text(b), "fuzz.toml").map(|_| ()).map_err(err)
    });
}

/// Measured run files (TTC `.dat`, `.mat` in both layouts, TYDEX) as `rigdata` reads them; the
/// seeds are a small synthetic TTC run written by rigdata's own writers. `libs/rigdata/tests/
/// no_panic.rs` adds structured corruptions (huge dimension fields, swapped lines) on top.
#[test]
fn measured_run_files() {
    use rigdata::fixture::{FixtureSpec, ttc_run};
    use rigdata::import::{FileFormat, ReadOptions, read_bytes};
    use rigdata::mat::{MatLayout, MatWriteOptions, to_mat};
    use rigdata::table::{DatLayout, to_dat};
    let spec =
        FixtureSpec { pressures_kpa: vec![83.0], loads_n: vec![1100.0], sweep_s: 3.0, ..FixtureSpec::cornering() };
    let table = ttc_run(&spec).table;
    let dat = to_dat(&table, DatLayout::default()).into_bytes();
    let read = |b: &[u8], f: FileFormat| read_bytes(b, "fuzz", f, &ReadOptions::default()).map(|_| ()).map_err(err);
    fuzz("TTC .dat", vec![dat.clone()], cases(BUDGET), |b| read(b, FileFormat::Dat));
    let mats = [MatLayout::Variables, MatLayout::Struct("run".into())]
        .into_iter()
        .map(|layout| to_mat(&table, &MatWriteOptions { compress: false, layout, ..Default::default() }).expect("mat"))
        .collect();
    fuzz("TTC .mat", mats, cases(BUDGET), |b| read(b, FileFormat::Mat));
    let data = read_bytes(&dat, "seed.dat", FileFormat::Dat, &ReadOptions::default()).expect("seed").0;
    let tdx = rigdata::tydex::to_tydex(&data, "fuzz").into_bytes();
    fuzz("TYDEX", vec![tdx], cases(BUDGET), |b| read(b, FileFormat::Tdx));
}

/// A small log: a few RigSamples over several chunks, metadata, a loss record.
fn small_log(dir: &Path) -> Vec<u8> {
    use tyre_msgs::{RigSample, std_msgs::Header};
    let path = dir.join("seed.mcap");
    let options = mcaplog::McapLogOptions { chunk_size_bytes: 2048, flush_interval_s: 0.05, zstd_level: 1 };
    let mut log = mcaplog::McapLog::create(&path, options).expect("create");
    let schema = tyre_msgs::schema::ros2msg_schema::<RigSample>().expect("schema");
    let ch = log.ensure_channel("/rig/sample", "tyre_msgs/msg/RigSample", &schema).expect("channel");
    let mut md = std::collections::BTreeMap::new();
    md.insert("software".to_owned(), "tyrerig".to_owned());
    log.write_metadata("tyrerig", &md).expect("metadata");
    let mut ledger = streamloss::LossLedger::new();
    for seq in [1u64, 2, 5] {
        ledger.observe("/rig/sample", 7, streamloss::SeqSource::Dds, seq);
    }
    log.write_metadata(streamloss::LOSS_RECORD, &ledger.report(true).to_entries()).expect("loss");
    for i in 0..40u64 {
        let s = RigSample { header: Header::iso_w(i as f64 * 0.01), seq: i, fx_n: i as f64, ..Default::default() };
        let data = mcaplog::codec::encode(&s, "RigSample").expect("encode");
        log.write(ch, i * 10_000_000, i * 10_000_000, &data).expect("write");
    }
    log.finish().expect("finish");
    std::fs::read(&path).expect("read seed")
}

#[test]
fn mcap_reading() {
    let dir = tempfile::tempdir().expect("tempdir");
    let seed = small_log(dir.path());
    fuzz("MCAP read (LogReader + typed + loss summary)", vec![seed], cases(BUDGET), |b| {
        let log = mcaplog::LogReader::from_bytes(Path::new("fuzz.mcap"), b).map_err(err)?;
        for t in log.topics() {
            if t.ros_type == "tyre_msgs/msg/RigSample" {
                log.typed::<tyre_msgs::RigSample>(&t.topic).map_err(err)?;
            }
        }
        let _ = log.loss_summary();
        Ok(())
    });
}

#[test]
fn mcap_recovery() {
    let dir = tempfile::tempdir().expect("tempdir");
    let seed = small_log(dir.path());
    let (input, output) = (dir.path().join("in.mcap"), dir.path().join("out.mcap"));
    fuzz("MCAP recover", vec![seed], cases(BUDGET), |b| {
        std::fs::write(&input, b).map_err(err)?;
        mcaplog::recover(&input, &output).map_err(err)?;
        // Whatever recovery keeps must be a valid log.
        mcaplog::LogReader::open(&output).map(|_| ()).map_err(|e| format!("recovered file unreadable: {e}"))
    });
}

#[test]
fn checkpoint_json() {
    let doc = procedure::load(&repo().join("launch-config/procedures/gs2mf_staticlong.toml")).expect("procedure");
    let plan = procedure::expand(&doc, &procedure::RunInputs::default()).expect("plan");
    let cfg = sequencer::SequencerConfig::default();
    let mut running = sequencer::Sequencer::new(plan.clone(), cfg).expect("sequencer");
    let start = tyre_msgs::ProcedureCommand { command: tyre_msgs::ProcedureCommand::START, ..Default::default() };
    running.on_command(0.0, &start).expect("start");
    for i in 0..3000 {
        running.step(f64::from(i) * 0.01, None, None);
    }
    let seed = serde_json::to_vec_pretty(&running.checkpoint()).expect("json");
    fuzz("checkpoint JSON (parse + resume + run)", vec![seed], cases(BUDGET), |b| {
        let cp: sequencer::Checkpoint = serde_json::from_slice(b).map_err(err)?;
        let mut s = sequencer::Sequencer::resume(plan.clone(), cfg, &cp).map_err(err)?;
        let _ = s.on_command(0.0, &start);
        for i in 0..50 {
            s.step(f64::from(i) * 0.01, None, None);
        }
        Ok(())
    });
}

#[test]
fn loss_record() {
    let mut ledger = streamloss::LossLedger::new();
    for seq in [1u64, 2, 9, 10, 30] {
        ledger.observe("/rig/sample", 0xabc, streamloss::SeqSource::Dds, seq);
    }
    ledger.malformed("/rig/sample");
    let entries = ledger.report(true).to_entries();
    let seed = entries.iter().map(|(k, v)| format!("{k}\t{v}\n")).collect::<String>().into_bytes();
    fuzz("loss record (MCAP metadata)", vec![seed], cases(BUDGET), |b| {
        let entries =
            text(b).lines().filter_map(|l| l.split_once('\t')).map(|(k, v)| (k.to_owned(), v.to_owned())).collect();
        streamloss::LossReport::from_entries(&entries).map(|r| drop(r.summary_lines())).map_err(err)
    });
}
