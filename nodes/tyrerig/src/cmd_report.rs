//! `tyrerig report <log.mcap> --out <dir>`: the end-of-run report. Replays the log's samples and
//! procedure states through the channels and monitor cores and writes `report.md` with the
//! thesis's plots, the derived measurements and every alarm (see `monitor::report` and
//! `docs/monitoring.md`).

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, ValueEnum};
use monitor::report::{self, Format};
use monitor::{MonitorConfig, TyreInfo};

/// Image formats of the plots.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ImageFormat {
    /// PNG (embedded in the Markdown).
    Png,
    /// SVG (embedded in the Markdown).
    Svg,
    /// Both; the Markdown embeds the PNGs.
    Both,
}

/// Arguments of `tyrerig report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// The MCAP log of a run (headless or recorded)
    pub log: PathBuf,
    /// Directory for report.md and the plots (created if missing)
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// ETRTO load index the tyre declares (default: from the log's `tyre` metadata)
    #[arg(long, value_name = "LI")]
    pub load_index: Option<u32>,
    /// Load index that was entered at the rig, if different from the declared one
    #[arg(long, value_name = "LI")]
    pub entered_load_index: Option<u32>,
    /// Tread depth of the new tyre [mm]
    #[arg(long, value_name = "MM", default_value_t = 5.6)]
    pub tread_new_mm: f64,
    /// Legal minimum tread depth [mm]
    #[arg(long, value_name = "MM", default_value_t = 1.6)]
    pub tread_min_mm: f64,
    /// Monitor thresholds (TOML, keys of monitor::MonitorConfig; defaults from the thesis)
    #[arg(long, value_name = "FILE")]
    pub monitor_config: Option<PathBuf>,
    /// Channels settings (TOML, keys of channels::ChannelsConfig)
    #[arg(long, value_name = "FILE")]
    pub channels_config: Option<PathBuf>,
    /// Plot format
    #[arg(long, value_enum, default_value_t = ImageFormat::Png)]
    pub format: ImageFormat,
}

/// Runs `tyrerig report`.
pub fn run(args: ReportArgs) -> anyhow::Result<()> {
    let read = |p: &PathBuf| std::fs::read_to_string(p).with_context(|| format!("{}: cannot read", p.display()));
    let monitor_cfg = match &args.monitor_config {
        Some(p) => MonitorConfig::from_toml(&read(p)?).with_context(|| format!("{}", p.display()))?,
        None => MonitorConfig::default(),
    };
    let channels_cfg = match &args.channels_config {
        Some(p) => channels::ChannelsConfig::from_toml(&read(p)?).with_context(|| format!("{}", p.display()))?,
        None => channels::ChannelsConfig::default(),
    };
    let tyre = match args.load_index {
        Some(li) => {
            let mut t = TyreInfo::from_load_index(li)?;
            t.entered_load_index = args.entered_load_index;
            t.tread_new_mm = args.tread_new_mm;
            t.tread_min_mm = args.tread_min_mm;
            t.validate()?;
            Some(t)
        }
        None => None,
    };
    let format = match args.format {
        ImageFormat::Png => Format::Png,
        ImageFormat::Svg => Format::Svg,
        ImageFormat::Both => Format::Both,
    };
    let (path, r) = report::run(&args.log, &args.out, tyre, channels_cfg, monitor_cfg, format)?;
    let level = match r.final_report.level {
        0 => "OK",
        1 => "WARN",
        _ => "ERROR",
    };
    println!(
        "{}: {} samples, verdict {level}, {} alarm(s), wear {:.2} mm, {} derived measurement(s)",
        path.display(),
        r.samples,
        r.alarms.len(),
        r.wear.map_or(f64::NAN, |w| w.wear_mm),
        r.derived.len()
    );
    for l in &r.data_loss {
        println!("  {l}");
    }
    Ok(())
}
