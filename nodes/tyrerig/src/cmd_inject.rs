//! `tyrerig inject`: hide known effects (thermal, wear, break-in) in recorded virtual-rig logs,
//! computed by the run's true tyre, and write what was hidden as JSON (`hidden` crate,
//! `docs/doctor-benchmark.md`).

use anyhow::{Context, Result, bail};
use clap::Args;
use hidden::{EffectKind, HiddenEffect, InjectionReport};
use rigsim::{NoiseParams, RigConfig, VirtualTyre};
use std::path::{Path, PathBuf};

/// Arguments of `tyrerig inject`.
#[derive(Debug, Args)]
pub struct InjectArgs {
    /// Recorded MCAP logs of one tyre compound (e.g. a TTC cornering and drive/brake pair): the
    /// effects are anchored to them together, their states start again in each
    #[arg(required = true)]
    pub logs: Vec<PathBuf>,
    /// The injected log to write, one per input log, in order
    #[arg(long, required = true)]
    pub out: Vec<PathBuf>,
    /// The virtual rig's config the logs were recorded with (its tyre is the true tyre; its
    /// noise the unit the sizes are given in)
    #[arg(long, default_value = "launch-config/virtual_rig.toml")]
    pub rig_config: PathBuf,
    /// An effect to hide, `thermal`, `wear` or `break_in`, optionally with a strength
    /// (`thermal:2`; default 1, 0 = none); repeatable
    #[arg(long = "effect", required = true, value_parser = parse_effect)]
    pub effects: Vec<(EffectKind, f64)>,
    /// Seed of the effects' forms (the same seed draws the same forms)
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write what was hidden (kinds, drawn and absolute parameters, sizes) as JSON
    #[arg(long)]
    pub truth_json: Option<PathBuf>,
}

/// `kind[:strength]`.
fn parse_effect(s: &str) -> Result<(EffectKind, f64), String> {
    let (name, strength) = s.split_once(':').unwrap_or((s, "1"));
    let kind = EffectKind::parse(name).ok_or_else(|| {
        format!("unknown effect {name:?}: expected one of {}", EffectKind::ALL.map(EffectKind::name).join(", "))
    })?;
    let strength: f64 = strength.trim().parse().map_err(|e| format!("strength {strength:?} of {name}: {e}"))?;
    if !strength.is_finite() || strength < 0.0 {
        return Err(format!("strength of {name} must be ≥ 0, not {strength}"));
    }
    Ok((kind, strength))
}

/// The true tyre and the noise of a rig config.
pub fn load_rig(path: &Path) -> Result<(VirtualTyre, NoiseParams)> {
    let cfg = RigConfig::load(path).with_context(|| format!("{}: cannot read the rig config", path.display()))?;
    let tyre = VirtualTyre::load(&cfg).with_context(|| format!("{}: cannot load its tyre", path.display()))?;
    Ok((tyre, cfg.noise))
}

/// The effects of `kinds` drawn with `seed`; a kind given twice is an error.
pub fn draw_effects(kinds: &[(EffectKind, f64)], seed: u64) -> Result<Vec<HiddenEffect>> {
    let mut out: Vec<HiddenEffect> = Vec::new();
    for &(kind, strength) in kinds {
        if out.iter().any(|e| e.kind() == kind) {
            bail!("--effect {kind} given twice");
        }
        out.push(HiddenEffect::draw(kind, seed, strength));
    }
    Ok(out)
}

/// The truth JSON: the report with the seed and rig config it was made with.
pub fn truth_json(report: &InjectionReport, seed: u64, rig_config: &Path) -> Result<serde_json::Value> {
    let mut v = serde_json::to_value(report).context("serialising the injection report")?;
    if let Some(m) = v.as_object_mut() {
        m.insert("tool".into(), "tyrerig inject".into());
        m.insert("seed".into(), seed.into());
        m.insert("rig_config".into(), rig_config.display().to_string().into());
        m.insert("kinds".into(), report.kinds().iter().map(|k| k.name()).collect::<Vec<_>>().into());
    }
    Ok(v)
}

/// Runs `tyrerig inject`.
pub fn run(args: InjectArgs) -> Result<()> {
    if args.out.len() != args.logs.len() {
        bail!("{} log(s) but {} --out path(s): give one --out per log, in order", args.logs.len(), args.out.len());
    }
    let (tyre, noise) = load_rig(&args.rig_config)?;
    let effects = draw_effects(&args.effects, args.seed)?;
    let pairs: Vec<(PathBuf, PathBuf)> = args.logs.iter().cloned().zip(args.out.iter().cloned()).collect();
    let t0 = std::time::Instant::now();
    let report = hidden::inject_logs(&pairs, &tyre, &noise, &effects)?;
    for l in &report.logs {
        println!(
            "{} → {}: {} RigSamples ({} in sweeps), forces changed in {}, DSTWOWHC in {}",
            l.input, l.output, l.samples, l.sweep_samples, l.forces_changed, l.radius_changed
        );
    }
    for e in &report.effects {
        let r = e.size.rms_in_sweeps;
        println!(
            "{} (strength {}): RMS in sweeps FX {:.1} N, FYW {:.1} N, MZW {:.2} N·m, DSTWOWHC {:.3} mm; \
             {:.1} σ of {} where it exceeds σ ({:.0} % of in-sweep samples)",
            e.kind,
            e.strength,
            r.fx_n,
            r.fyw_n,
            r.mzw_nm,
            r.dstwowhc_m * 1e3,
            e.size.strength_noise_units,
            e.size.main_channel,
            100.0 * e.size.region_share
        );
    }
    if let Some(path) = &args.truth_json {
        let v = truth_json(&report, args.seed, &args.rig_config)?;
        let text = serde_json::to_string_pretty(&v).context("serialising the truth")?;
        std::fs::write(path, text).with_context(|| format!("{}: cannot write", path.display()))?;
        println!("truth: {}", path.display());
    }
    println!("wall time {:.1} s", t0.elapsed().as_secs_f64());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn effects_parse_with_and_without_a_strength() {
        assert_eq!(parse_effect("thermal"), Ok((EffectKind::Thermal, 1.0)));
        assert_eq!(parse_effect("break-in:2.5"), Ok((EffectKind::BreakIn, 2.5)));
        assert!(parse_effect("pressure").is_err());
        assert!(parse_effect("wear:-1").is_err());
        assert!(parse_effect("wear:x").is_err());
        assert!(draw_effects(&[(EffectKind::Wear, 1.0), (EffectKind::Wear, 2.0)], 1).is_err());
    }
}
