use rigsim::calibration::*;
fn main() {
    let cfg = rigsim::RigConfig::load(std::path::Path::new("launch-config/virtual_rig.toml")).unwrap();
    let p = rigsim::TyreParams::read_tir(&cfg.tyre_file).unwrap();
    let which = std::env::args().nth(1).unwrap_or("fr".into());
    let kind = match std::env::args().nth(2).as_deref() {
        Some("low") => SweepKind::ConstantLow,
        Some("var") => SweepKind::Variable,
        _ => SweepKind::ConstantHigh,
    };
    let s = if which == "fr" { freerolling_setup(kind) } else { brkdrv_setup(kind) };
    let pre = preconditioned_rig(&cfg, &p).unwrap();
    let o = comparison_sweep(&pre, &s).unwrap();
    let mut prev: Option<&rigsim::RigSample> = None;
    for x in &o.samples {
        let sl = if which == "fr" { x.slipangl_deg } else { x.longslip * 100.0 };
        if let Some(pv) = prev {
            let ps = if which == "fr" { pv.slipangl_deg } else { pv.longslip * 100.0 };
            if ps.signum() != sl.signum() && x.runtime_s < o.start_time_s + o.sweep_s + 0.3 {
                println!(
                    "t {:.3} slip {:.4} -> {:.4}  fy {:.0} fx {:.0}",
                    x.runtime_s - o.start_time_s,
                    ps,
                    sl,
                    x.fyw_n,
                    x.fx_n
                );
            }
        }
        prev = Some(x);
    }
    println!("hyst {:.0} peak {:.1} cool {:.1}", o.hysteresis_n, o.peak_temp_c, o.cool_s);
}
