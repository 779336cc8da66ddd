//! Report: `doctor.json`, `report.md`, PNG plots and the extended `.tir`.

use crate::DoctorError;
use crate::data::Dataset;
use crate::diagnose::{CandidateScore, Diagnosis, NamedEffect, p_text};
use crate::effects::{CH_FX, CH_FY, CH_MZ, CH_RL, CHANNELS, EffectParams};
use crate::extension::extended_params;
use mftyre::TyreParams;
use plotters::prelude::*;
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Files a report wrote.
#[derive(Debug, Clone)]
pub struct Written {
    /// `doctor.json`.
    pub json: PathBuf,
    /// `report.md`.
    pub markdown: PathBuf,
    /// The extended model (only when an effect was named).
    pub model: Option<PathBuf>,
    /// Plots.
    pub plots: Vec<PathBuf>,
}

fn werr(path: &Path, e: impl std::fmt::Display) -> DoctorError {
    DoctorError::Write { path: path.display().to_string(), detail: e.to_string() }
}

/// Unit scale for display: DSTWOWHC in mm.
fn disp(ch: usize) -> (f64, &'static str) {
    match ch {
        CH_RL => (1e3, "mm"),
        CH_MZ => (1.0, "N·m"),
        _ => (1.0, "N"),
    }
}

fn ch_index(name: &str) -> usize {
    CHANNELS.iter().position(|c| *c == name).unwrap_or(CH_FY)
}

/// The extended model of a diagnosis (`None` when nothing was named).
pub fn extended_model(base: &TyreParams, dx: &Diagnosis) -> Option<TyreParams> {
    if dx.named.is_empty() {
        return None;
    }
    let effects: Vec<EffectParams> = dx.named.iter().map(|n| n.params.clone()).collect();
    Some(extended_params(base, &effects, &dx.references))
}

fn score_json(c: &CandidateScore) -> Value {
    json!({
        "effect": c.effect.name(),
        "testable": c.testable,
        "reason": c.reason,
        "n_params": c.n_params,
        "evidence": c.evidence,
        "chi2_before_heldout": c.chi2_before_heldout,
        "chi2_after_heldout": c.chi2_after_heldout,
        "folds_improved": c.folds_improved,
        "folds": c.folds,
        "delta_chi2_by_channel": CHANNELS.iter().zip(c.delta_chi2_by_channel).map(|(k, v)| (k.to_string(), json!(v))).collect::<serde_json::Map<_, _>>(),
        "significant": c.significant,
        "p_value": c.p_value,
        "p_needed": c.p_needed,
        "family": c.family,
        "form_corrected": c.form_corrected,
        "support": c.support,
    })
}

/// `doctor.json` as a value.
pub fn to_json(
    dx: &Diagnosis,
    sources: &[String],
    base_name: &str,
    model_file: Option<&str>,
    wall_time_s: f64,
) -> Value {
    let per_ch =
        |v: [f64; 4]| CHANNELS.iter().zip(v).map(|(k, x)| (k.to_string(), json!(x))).collect::<serde_json::Map<_, _>>();
    json!({
        "tool": "tyrerig doctor",
        "format_version": 1,
        "logs": sources,
        "base_model": base_name,
        "points": dx.points,
        "sweeps": dx.sweeps,
        "noise_floor": per_ch(dx.rms.noise),
        "named_effects": dx.state_effects().map(|n| n.effect.name()).collect::<Vec<_>>(),
        "indistinct_effects": dx.indistinct_effects().map(|n| json!({
            "in_model": n.effect.name(),
            "or": n.indistinct_from.map(|e| e.name()),
        })).collect::<Vec<_>>(),
        "form_errors": dx.form_errors().map(|n| n.effect.name()).collect::<Vec<_>>(),
        "not_identifiable": dx.not_identifiable,
        "dropped": dx.dropped,
        "ties": dx.ties,
        "written_model_worse": dx.written_model_worse,
        "backward_check": dx.backward_check.iter().map(|b| json!({
            "effect": b.score.effect.name(),
            "beside": b.beside.iter().map(|e| e.name()).collect::<Vec<_>>(),
            "evidence": b.score.evidence,
            "p_value": b.score.p_value,
            "folds_improved": b.score.folds_improved,
            "significant": b.score.significant,
        })).collect::<Vec<_>>(),
        "effects": dx.named.iter().map(|n| json!({
            "effect": n.effect.name(),
            "evidence": n.evidence,
            "runner_up": n.runner_up.map(|(e, v)| json!({"effect": e.name(), "evidence": v})),
            "channel": n.channel,
            "region": n.region,
            "region_points": n.region_points,
            "rms_before": n.rms_before,
            "rms_after": n.rms_after,
            "rms_before_heldout": n.rms_before_heldout,
            "rms_after_heldout": n.rms_after_heldout,
            "form_corrected": n.form_corrected,
            "correlation": n.correlation,
            "parameters": n.params.keys.iter().zip(&n.params.values).map(|(k, v)| (k.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
            "family": n.family,
            "p_value": n.p_value,
            "channels_heldout": CHANNELS.iter().zip(n.channels_heldout).map(|(k, [b, a])| (k.to_string(), json!({"before": b, "after": a}))).collect::<serde_json::Map<_, _>>(),
        })).collect::<Vec<_>>(),
        "rounds": dx.rounds.iter().map(|r| r.iter().map(score_json).collect::<Vec<_>>()).collect::<Vec<_>>(),
        "regions": dx.regions.iter().map(|b| json!({
            "variable": b.variable, "bin": b.bin, "n": b.n, "flagged": b.flagged,
            "rms_over_noise": per_ch(b.rms_over_noise),
        })).collect::<Vec<_>>(),
        "rms": {
            "base": per_ch(dx.rms.base),
            "final_fit": per_ch(dx.rms.final_fit),
            "final_heldout": per_ch(dx.rms.final_heldout),
        },
        "thermal_reference_temp_c": dx.references.t_ref_c,
        "laser_flash_decay_s": dx.flash_decay_s,
        "stop_reason": dx.stop_reason,
        "not_diagnosed": dx.not_diagnosed,
        "form_correction": dx.form_correction,
        "extended_model": model_file,
        "wall_time_s": wall_time_s,
    })
}

/// Writes everything into `out_dir`: `doctor.json`, `report.md`, plots, and
/// `<base stem>_doctor.tir` when an effect was named.
pub fn write_all(
    out_dir: &Path,
    ds: &Dataset,
    base: &TyreParams,
    dx: &Diagnosis,
    base_name: &str,
    wall_time_s: f64,
) -> Result<Written, DoctorError> {
    std::fs::create_dir_all(out_dir).map_err(|e| werr(out_dir, e))?;
    let stem = Path::new(base_name).file_stem().and_then(|s| s.to_str()).unwrap_or("model").to_owned();
    let model = match extended_model(base, dx) {
        Some(p) => {
            let path = out_dir.join(format!("{stem}_doctor.tir"));
            std::fs::write(&path, p.to_tir_string()).map_err(|e| werr(&path, e))?;
            Some(path)
        }
        None => None,
    };
    let mut plots = Vec::new();
    let p = out_dir.join("regions.png");
    plot_regions(&p, dx)?;
    plots.push(p);
    for (n, ne) in dx.named.iter().enumerate() {
        let p = out_dir.join(format!("effect{}_{}_residual.png", n + 1, ne.effect.name()));
        plot_residual(&p, ds, dx, n)?;
        plots.push(p);
        let p = out_dir.join(format!("effect{}_{}_overlay.png", n + 1, ne.effect.name()));
        plot_overlay(&p, ds, dx, n)?;
        plots.push(p);
    }
    let model_name = model.as_ref().and_then(|p| p.file_name()).map(|s| s.to_string_lossy().into_owned());
    let json_path = out_dir.join("doctor.json");
    let v = to_json(dx, &ds.sources, base_name, model_name.as_deref(), wall_time_s);
    std::fs::write(&json_path, serde_json::to_string_pretty(&v).unwrap_or_default())
        .map_err(|e| werr(&json_path, e))?;
    let md_path = out_dir.join("report.md");
    std::fs::write(&md_path, markdown(ds, dx, base_name, model_name.as_deref(), &plots, wall_time_s))
        .map_err(|e| werr(&md_path, e))?;
    Ok(Written { json: json_path, markdown: md_path, model, plots })
}

fn fmt_rms(x: f64, ch: usize) -> String {
    let (s, u) = disp(ch);
    format!("{:.3} {u}", x * s)
}

/// The Markdown report.
pub fn markdown(
    ds: &Dataset,
    dx: &Diagnosis,
    base_name: &str,
    model_file: Option<&str>,
    plots: &[PathBuf],
    wall_time_s: f64,
) -> String {
    let mut m = String::new();
    let _ = writeln!(m, "# tyrerig doctor report\n");
    let _ = writeln!(m, "- Logs: {}", ds.sources.join(", "));
    let _ = writeln!(m, "- Base model: `{base_name}`");
    let _ = writeln!(m, "- Data: {} points in {} sweeps; wall time {:.1} s\n", dx.points, dx.sweeps, wall_time_s);
    let _ = writeln!(m, "## Verdict\n");
    let line = |m: &mut String, i: usize, n: &NamedEffect| {
        let ch = ch_index(&n.channel);
        let ru = n.runner_up.map_or("none".to_owned(), |(e, v)| format!("{} ({:.3})", e.name(), v));
        let _ = writeln!(
            m,
            "{}. **{}** — evidence {:.3}, bootstrap p {} (runner-up {ru}); main channel {}; held-out RMS in its region {} → {} ({:.0} % less).",
            i + 1,
            n.effect.name(),
            n.evidence,
            p_text(n.p_value),
            n.channel,
            fmt_rms(n.rms_before_heldout, ch),
            fmt_rms(n.rms_after_heldout, ch),
            n.region_cut_pct()
        );
    };
    if dx.state_effects().next().is_none() {
        let _ = writeln!(m, "**No missing effect of the tyre's state named.**\n");
    } else {
        let _ = writeln!(m, "Missing effects of the tyre's state, in the order added:\n");
        for (i, n) in dx.state_effects().enumerate() {
            line(&mut m, i, n);
        }
        let _ = writeln!(m);
    }
    // A heading and its numbered effects, when there are any.
    let list = |m: &mut String, heading: &str, effects: Vec<&NamedEffect>| {
        if effects.is_empty() {
            return;
        }
        let _ = writeln!(m, "{heading}\n");
        for (i, n) in effects.into_iter().enumerate() {
            line(m, i, n);
        }
        let _ = writeln!(m);
    };
    list(
        &mut m,
        "A state effect in the logs that they cannot name (held in the model for its prediction; why, below):",
        dx.indistinct_effects().collect(),
    );
    list(
        &mut m,
        "The model's form error (operating-point misfits MF-Tyre 6.1's own coefficients mend; not effects of the tyre's state):",
        dx.form_errors().collect(),
    );
    for w in &dx.written_model_worse {
        let _ = writeln!(m, "- **Warning**: {w}.");
    }
    for ni in dx.not_identifiable.iter().chain(&dx.dropped).chain(&dx.ties) {
        let _ = writeln!(m, "- {ni}.");
    }
    if !dx.not_identifiable.is_empty()
        || !dx.dropped.is_empty()
        || !dx.ties.is_empty()
        || !dx.written_model_worse.is_empty()
    {
        let _ = writeln!(m);
    }
    let _ = writeln!(m, "Search stopped: {}\n", dx.stop_reason);
    if let Some(f) = model_file {
        let _ = writeln!(m, "Extended model: `{f}` (section `[TYRERIG_EXTENSIONS]`, see docs/doctor.md).\n");
    }
    for nd in &dx.not_diagnosed {
        let _ = writeln!(m, "- {nd}");
    }
    if !dx.not_diagnosed.is_empty() {
        let _ = writeln!(m);
    }
    let _ = writeln!(m, "## 1. Simulate: residuals and noise floor\n");
    let _ = writeln!(m, "| channel | noise σ | base RMS | final RMS (fit) | final RMS (held-out) |");
    let _ = writeln!(m, "|---|---|---|---|---|");
    for ch in [CH_FX, CH_FY, CH_MZ, CH_RL] {
        let _ = writeln!(
            m,
            "| {} | {} | {} | {} | {} |",
            CHANNELS[ch],
            fmt_rms(dx.rms.noise[ch], ch),
            fmt_rms(dx.rms.base[ch], ch),
            fmt_rms(dx.rms.final_fit[ch], ch),
            fmt_rms(dx.rms.final_heldout[ch], ch)
        );
    }
    let _ = writeln!(
        m,
        "\nNoise σ: point-to-point scatter of the base residual along each sweep (robust second difference).\n"
    );
    let taus: Vec<String> =
        dx.flash_decay_s.iter().map(|t| t.map_or("none evident".to_owned(), |t| format!("τ = {t:.2} s"))).collect();
    let _ = writeln!(
        m,
        "Grip temperature: quiet tread-laser readings with the flash's decay fitted out (per log: {}); reference {:.1} °C.\n",
        taus.join(", "),
        dx.references.t_ref_c
    );
    let _ = writeln!(m, "## 2. Find: where the base model disagrees beyond noise\n");
    let flagged: Vec<_> = dx.regions.iter().filter(|b| b.flagged).collect();
    if flagged.is_empty() {
        let _ = writeln!(m, "No region's residual exceeds 1.3 σ.\n");
    } else {
        let _ = writeln!(m, "| variable | bin | points | FX/σ | FYW/σ | MZW/σ | DSTWOWHC/σ |");
        let _ = writeln!(m, "|---|---|---|---|---|---|---|");
        for b in flagged {
            let r = b.rms_over_noise;
            let _ = writeln!(
                m,
                "| {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} |",
                b.variable.replace('|', "\\|"),
                b.bin,
                b.n,
                r[0],
                r[1],
                r[2],
                r[3]
            );
        }
    }
    let _ = writeln!(m, "\n![regions](regions.png)\n");
    let _ = writeln!(m, "## 3. Name: candidate effects, scored on held-out sweeps\n");
    let _ = writeln!(
        m,
        "Evidence = (held-out χ² reduction − k·ln N) / held-out χ² of the model so far; named when ≥ the threshold, better on all held-out folds but at most one, and its gain is consistent over sweeps (block bootstrap p ≤ the false-naming rate shared among the round's candidates); then only if it cuts the held-out residual in its own region and makes no channel worse.\n"
    );
    for (r, round) in dx.rounds.iter().enumerate() {
        let _ = writeln!(m, "### Round {}\n", r + 1);
        let _ = writeln!(
            m,
            "| candidate | family | params | evidence | p (needed) | folds improved | held-out χ² before → after | note |"
        );
        let _ = writeln!(m, "|---|---|---|---|---|---|---|---|");
        let mut sorted: Vec<&CandidateScore> = round.iter().collect();
        sorted.sort_by(|a, b| b.evidence.total_cmp(&a.evidence));
        for c in sorted {
            let note = if !c.testable {
                format!("not testable: {}", c.reason)
            } else if c.significant {
                if c.reason.is_empty() { "significant".to_owned() } else { c.reason.clone() }
            } else if !c.reason.is_empty() {
                c.reason.clone()
            } else {
                String::new()
            };
            let fam = match c.family {
                crate::effects::Family::State => "state",
                crate::effects::Family::FormError => "form error",
            };
            let _ = writeln!(
                m,
                "| {} | {fam} | {} | {:.4} | {} ({:.4}) | {}/{} | {:.0} → {:.0} | {note} |",
                c.effect.name(),
                c.n_params,
                c.evidence,
                p_text(c.p_value),
                c.p_needed,
                c.folds_improved,
                c.folds,
                c.chi2_before_heldout,
                c.chi2_after_heldout
            );
        }
        let _ = writeln!(m);
    }
    if !dx.backward_check.is_empty() {
        let _ = writeln!(m, "### Backward check: each state effect as the last addition\n");
        let _ = writeln!(m, "| effect | beside | evidence | p | folds improved | verdict |");
        let _ = writeln!(m, "|---|---|---|---|---|---|");
        for b in &dx.backward_check {
            let beside: Vec<&str> = b.beside.iter().map(|e| e.name()).collect();
            let s = &b.score;
            let verdict = if s.significant { "significant".to_owned() } else { s.reason.clone() };
            let _ = writeln!(
                m,
                "| {} | {} | {:.4} | {} | {}/{} | {verdict} |",
                s.effect.name(),
                beside.join(", "),
                s.evidence,
                p_text(s.p_value),
                s.folds_improved,
                s.folds
            );
        }
        let _ = writeln!(m);
    }
    let _ = writeln!(m, "## 4–5. Add and show\n");
    for (i, n) in dx.named.iter().enumerate() {
        let ch = ch_index(&n.channel);
        let _ = writeln!(m, "### {}. {}\n", i + 1, n.effect.name());
        let _ = writeln!(m, "Region: {}.\n", n.region);
        let _ = writeln!(m, "Correlation of the residual with the effect's predicted change: {:.3}.\n", n.correlation);
        if n.form_corrected {
            let _ = writeln!(
                m,
                "Scored against the present model plus its form error (the residual other sweeps show at the same operating point, cross-fitted): the RMS below is what that leaves.\n"
            );
        }
        let _ = writeln!(m, "| {} RMS in the region | before | after | change |", n.channel);
        let _ = writeln!(m, "|---|---|---|---|");
        for (what, b, a) in [
            ("fit (all sweeps)", n.rms_before, n.rms_after),
            ("held-out sweeps", n.rms_before_heldout, n.rms_after_heldout),
        ] {
            let _ = writeln!(
                m,
                "| {what} | {} | {} | {:+.0} % |",
                fmt_rms(b, ch),
                fmt_rms(a, ch),
                100.0 * (a / b.max(1e-30) - 1.0)
            );
        }
        let _ = writeln!(m, "\nEvery channel on held-out sweeps, all points (adding never harms):\n");
        let _ = writeln!(m, "| channel | before | after |");
        let _ = writeln!(m, "|---|---|---|");
        for (c, [b, a]) in n.channels_heldout.iter().enumerate() {
            if *b > 0.0 {
                let _ = writeln!(m, "| {} | {} | {} |", CHANNELS[c], fmt_rms(*b, c), fmt_rms(*a, c));
            }
        }
        let _ = writeln!(m, "\nParameters:\n");
        for (k, v) in n.params.keys.iter().zip(&n.params.values) {
            let _ = writeln!(m, "- `{k}` = {v:.6}");
        }
        for p in plots {
            let name = p.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            if name.starts_with(&format!("effect{}_", i + 1)) {
                let _ = writeln!(m, "\n![{name}]({name})");
            }
        }
        let _ = writeln!(m);
    }
    m
}

fn err<E: std::fmt::Debug>(path: &Path) -> impl Fn(E) -> DoctorError + '_ {
    move |e| werr(path, format!("{e:?}"))
}

fn bounds(pts: impl Iterator<Item = (f64, f64)>) -> (f64, f64, f64, f64) {
    let mut b = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for (x, y) in pts {
        if x.is_finite() && y.is_finite() {
            b = (b.0.min(x), b.1.max(x), b.2.min(y), b.3.max(y));
        }
    }
    if !b.0.is_finite() {
        return (0.0, 1.0, 0.0, 1.0);
    }
    let px = (b.1 - b.0).abs().max(1e-9) * 0.05;
    let py = (b.3 - b.2).abs().max(1e-9) * 0.05;
    (b.0 - px, b.1 + px, b.2 - py, b.3 + py)
}

fn plot_residual(path: &Path, ds: &Dataset, dx: &Diagnosis, n: usize) -> Result<(), DoctorError> {
    let ne = &dx.named[n];
    let ch = ch_index(&ne.channel);
    let (sc, unit) = disp(ch);
    let before = &dx.plot.before_heldout[n];
    let after = &dx.plot.after_heldout[n];
    let meas = &dx.plot.meas;
    let xs: Vec<f64> = ds.points.iter().map(|&i| ne.effect.variable_value(ds, i)).collect();
    let pb: Vec<(f64, f64)> = xs.iter().enumerate().map(|(k, &x)| (x, (meas[k][ch] - before[k][ch]) * sc)).collect();
    let pa: Vec<(f64, f64)> = xs.iter().enumerate().map(|(k, &x)| (x, (meas[k][ch] - after[k][ch]) * sc)).collect();
    let (x0, x1, y0, y1) = bounds(pb.iter().chain(&pa).copied());
    let root = BitMapBackend::new(path, (1000, 650)).into_drawing_area();
    root.fill(&WHITE).map_err(err(path))?;
    let (vname, vunit) = ne.effect.variable();
    let mut ctx = ChartBuilder::on(&root)
        .caption(format!("{}: {} residual vs {} (held-out)", ne.effect.name(), ne.channel, vname), ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(42)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err(path))?;
    ctx.configure_mesh()
        .x_desc(format!("{vname} [{vunit}]"))
        .y_desc(format!("{} measured − model [{unit}]", ne.channel))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err(path))?;
    ctx.draw_series(
        pb.iter().filter(|p| p.1.is_finite()).map(|&p| Circle::new(p, 2, RGBColor(200, 80, 60).mix(0.5).filled())),
    )
    .map_err(err(path))?
    .label("before")
    .legend(|(x, y)| Circle::new((x, y), 4, RGBColor(200, 80, 60).filled()));
    ctx.draw_series(
        pa.iter().filter(|p| p.1.is_finite()).map(|&p| Circle::new(p, 2, RGBColor(40, 90, 200).mix(0.6).filled())),
    )
    .map_err(err(path))?
    .label(format!("after ({} added)", ne.effect.name()))
    .legend(|(x, y)| Circle::new((x, y), 4, RGBColor(40, 90, 200).filled()));
    ctx.configure_series_labels().background_style(WHITE.mix(0.85)).border_style(BLACK).draw().map_err(err(path))?;
    root.present().map_err(err(path))?;
    Ok(())
}

fn plot_overlay(path: &Path, ds: &Dataset, dx: &Diagnosis, n: usize) -> Result<(), DoctorError> {
    let ne = &dx.named[n];
    let mut ch = ch_index(&ne.channel);
    if ch == CH_RL || ch == CH_FX && !ds.has_longitudinal() {
        ch = CH_FY;
    }
    let before = &dx.plot.before[n];
    let after = &dx.plot.after[n];
    let meas = &dx.plot.meas;
    // The sweep with the most region points.
    let mut counts = vec![0usize; ds.sweeps.len()];
    for &k in &dx.plot.region[n] {
        counts[ds.point_sweep(k)] += 1;
    }
    let sweep = (0..counts.len()).max_by_key(|&s| counts[s]).unwrap_or(0);
    let ks: Vec<usize> = (0..ds.len()).filter(|&k| ds.point_sweep(k) == sweep).collect();
    let long = ds.sweeps.get(sweep).is_some_and(|s| s.coupled);
    let x = |k: usize| {
        let i = ds.points[k];
        if long { ds.series.kappa[i] * 100.0 } else { ds.series.alpha_deg[i] }
    };
    let (sc, unit) = disp(ch);
    let pm: Vec<(f64, f64)> = ks.iter().map(|&k| (x(k), meas[k][ch] * sc)).collect();
    let pb: Vec<(f64, f64)> = ks.iter().map(|&k| (x(k), before[k][ch] * sc)).collect();
    let pa: Vec<(f64, f64)> = ks.iter().map(|&k| (x(k), after[k][ch] * sc)).collect();
    let (x0, x1, y0, y1) = bounds(pm.iter().chain(&pb).chain(&pa).copied());
    let root = BitMapBackend::new(path, (1000, 650)).into_drawing_area();
    root.fill(&WHITE).map_err(err(path))?;
    let title = ds.sweeps.get(sweep).map_or(String::new(), |s| s.name.clone());
    let mut ctx = ChartBuilder::on(&root)
        .caption(format!("model over data: {title}"), ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(42)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err(path))?;
    ctx.configure_mesh()
        .x_desc(if long { "LONGSLIP [%]" } else { "SLIPANGL [deg]" })
        .y_desc(format!("{} [{unit}]", CHANNELS[ch]))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err(path))?;
    ctx.draw_series(pm.iter().map(|&p| Circle::new(p, 2, BLACK.mix(0.5).filled())))
        .map_err(err(path))?
        .label("measured")
        .legend(|(x, y)| Circle::new((x, y), 4, BLACK.filled()));
    ctx.draw_series(LineSeries::new(pb.iter().copied(), RGBColor(200, 80, 60).stroke_width(2)))
        .map_err(err(path))?
        .label("before")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], RGBColor(200, 80, 60).stroke_width(2)));
    ctx.draw_series(LineSeries::new(pa.iter().copied(), RGBColor(40, 90, 200).stroke_width(2)))
        .map_err(err(path))?
        .label(format!("with {}", ne.effect.name()))
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], RGBColor(40, 90, 200).stroke_width(2)));
    ctx.configure_series_labels().background_style(WHITE.mix(0.85)).border_style(BLACK).draw().map_err(err(path))?;
    root.present().map_err(err(path))?;
    Ok(())
}

fn plot_regions(path: &Path, dx: &Diagnosis) -> Result<(), DoctorError> {
    let root = BitMapBackend::new(path, (1500, 1000)).into_drawing_area();
    root.fill(&WHITE).map_err(err(path))?;
    let mut vars: Vec<&str> = Vec::new();
    for b in &dx.regions {
        if !vars.contains(&b.variable.as_str()) {
            vars.push(&b.variable);
        }
    }
    let panels = root.split_evenly((3, 3));
    for (panel, var) in panels.iter().zip(&vars) {
        let bins: Vec<_> = dx.regions.iter().filter(|b| b.variable == *var).collect();
        let ymax = bins.iter().flat_map(|b| b.rms_over_noise).filter(|v| v.is_finite()).fold(2.0f64, f64::max) * 1.1;
        let mut ctx = ChartBuilder::on(panel)
            .caption(format!("{var}: RMS/σ"), ("sans-serif", 15))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(40)
            .build_cartesian_2d(-0.5..(bins.len() as f64 - 0.5), 0.0..ymax)
            .map_err(err(path))?;
        let labels: Vec<String> = bins.iter().map(|b| b.bin.clone()).collect();
        ctx.configure_mesh()
            .x_labels(bins.len().max(1))
            .x_label_formatter(&|x| {
                let i = x.round();
                if (x - i).abs() < 0.01 && i >= 0.0 {
                    labels.get(i as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .label_style(("sans-serif", 10))
            .disable_x_mesh()
            .draw()
            .map_err(err(path))?;
        ctx.draw_series(LineSeries::new([(-0.5, 1.0), (bins.len() as f64 - 0.5, 1.0)], BLACK.mix(0.5)))
            .map_err(err(path))?;
        let colors = [RGBColor(90, 90, 90), RGBColor(200, 80, 60), RGBColor(40, 90, 200), RGBColor(60, 160, 60)];
        for (ch, color) in colors.iter().enumerate() {
            let off = (ch as f64 - 1.5) * 0.15;
            ctx.draw_series(bins.iter().enumerate().filter(|(_, b)| b.rms_over_noise[ch].is_finite()).map(|(i, b)| {
                Rectangle::new(
                    [(i as f64 + off - 0.07, 0.0), (i as f64 + off + 0.07, b.rms_over_noise[ch])],
                    color.filled(),
                )
            }))
            .map_err(err(path))?;
        }
    }
    root.present().map_err(err(path))?;
    Ok(())
}
