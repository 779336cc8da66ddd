//! `tyrerig mcap …`: inspect and repair logs.

use recorder::{LogReader, recover};
use std::path::PathBuf;

#[derive(Debug, clap::Subcommand)]
pub enum McapCmd {
    /// Rescue a log cut short (recorder killed, disk full): every complete chunk is kept.
    Recover {
        /// The damaged log.
        input: PathBuf,
        /// Where to write the repaired log (default: `<input>.recovered.mcap`).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Topics, types, message counts, time span and metadata of a log.
    Info {
        /// The log.
        file: PathBuf,
    },
}

pub fn run(cmd: McapCmd) -> anyhow::Result<()> {
    match cmd {
        McapCmd::Recover { input, output } => {
            let output = output.unwrap_or_else(|| {
                let mut s = input.clone().into_os_string();
                s.push(".recovered.mcap");
                PathBuf::from(s)
            });
            let report = recover::recover(&input, &output)?;
            println!(
                "{}: recovered {} messages on {} channels and {} metadata records → {}",
                input.display(),
                report.messages,
                report.channels,
                report.metadata_records,
                output.display()
            );
            match report.stopped_at {
                Some(why) => println!("reading stopped at the first damaged record: {why}"),
                None => println!("the input was complete; nothing was lost"),
            }
            Ok(())
        }
        McapCmd::Info { file } => {
            let log = LogReader::open(&file)?;
            println!("{}", file.display());
            for (name, entries) in log.metadata() {
                if name == streamloss::LOSS_RECORD {
                    continue; // summarised below
                }
                println!("  metadata {name}:");
                for (k, v) in entries {
                    println!("    {k} = {v}");
                }
            }
            println!("  {:<32} {:<40} {:>10} {:>10}", "topic", "type", "messages", "span s");
            for t in log.topics() {
                let span = (t.last_log_time_ns - t.first_log_time_ns) as f64 * 1e-9;
                println!("  {:<32} {:<40} {:>10} {:>10.2}", t.topic, t.ros_type, t.messages, span);
            }
            for line in loss_lines(&log) {
                println!("  {line}");
            }
            Ok(())
        }
    }
}

/// The log's loss summary, with every writer's gap ranges.
pub fn loss_lines(log: &LogReader) -> Vec<String> {
    let mut out = log.loss_summary().lines;
    if let Some(Ok(r)) = log.loss_report() {
        for s in r.streams.iter().filter(|s| s.lost > 0) {
            let more = s.gaps_total.saturating_sub(s.gaps.len() as u64);
            out.push(format!(
                "  {} {} writer {:032x}: gaps {}{}",
                s.topic,
                s.source.as_str(),
                s.writer,
                s.gaps.iter().map(ToString::to_string).collect::<Vec<_>>().join(" "),
                if more > 0 { format!(" and {more} more") } else { String::new() }
            ));
        }
    }
    out
}
