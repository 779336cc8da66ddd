//! Prints what the shipped procedure files expand to (thesis's tyre: load index 110,
//! 2.1/2.6/3.3 bar, 16.6 m/s, default rig limits).
//!
//! ```text
//! cargo run -p procedure --example plan                       # planned times of every file
//! cargo run -p procedure --example plan -- gs2mf_brkdrv.toml  # one file, step by step
//! ```

use procedure::{PauseModel, Plan, RunInputs, SweepStyle, expand, load};
use std::path::PathBuf;
use std::process::ExitCode;

fn plan(name: &str, sweeps: SweepStyle) -> Result<Plan, String> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/procedures").join(name);
    let doc = load(&path).map_err(|e| e.to_string())?;
    expand(&doc, &RunInputs { sweeps, ..RunInputs::default() }).map_err(|e| e.to_string())
}

fn listing(file: &str) -> Result<(), String> {
    let p = plan(file, SweepStyle::Variable)?;
    for st in &p.steps {
        let sp = st.trajectory.start();
        println!(
            "{:4} {:15} {:58} {:7.2} s  fz {:7.0} N  SA {:6.2}  camber {:5.2}  p {:4.2} bar  v {:5.2}  {}{}",
            st.index,
            format!("{:?}", st.kind),
            st.name,
            st.duration_s,
            sp.fz_n,
            sp.slip_angle_deg,
            sp.camber_deg,
            sp.pressure_bar,
            sp.speed_mps,
            p.sections[st.section_index].name,
            if st.thermal_pause_after { "  +pause" } else { "" }
        );
    }
    Ok(())
}

fn summaries() -> Result<(), String> {
    let m = PauseModel::default();
    for f in
        ["gs2mf_freerolling.toml", "gs2mf_brkdrv.toml", "gs2mf_staticlong.toml", "gs2mf.toml", "square_matrix.toml"]
    {
        for style in [SweepStyle::Variable, SweepStyle::Continuous] {
            let p = plan(f, style)?;
            let s = p.summary();
            println!(
                "{f:24} {style:?}: setpoint {:6.0} s, with pauses {:6.0} s, sweeps {}, data steps {}, pauses {}, tyre changes {}",
                s.setpoint_time_s,
                p.estimate_total_s(&m),
                s.sweeps,
                s.data_steps,
                s.thermal_pauses,
                s.tyre_changes
            );
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let result = match std::env::args().nth(1) {
        Some(file) => listing(&file),
        None => summaries(),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}
