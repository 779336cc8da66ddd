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
            Ok(())
        }
    }
}
