use rigsim::calibration::*;
fn main() {
    let cfg = rigsim::RigConfig::load(std::path::Path::new("launch-config/virtual_rig.toml")).unwrap();
    let p = rigsim::TyreParams::read_tir(&cfg.tyre_file).unwrap();
    let pre = preconditioned_rig(&cfg, &p).unwrap();
    for kind in SweepKind::ALL {
        let s = freerolling_setup(kind);
        let mut rig = pre.clone();
        let mut sink = Vec::new();
        thermal_pause(&mut rig, &s, BASELINE_C, 300.0, &mut sink).unwrap();
        let (mut gmin, mut tmax) = (1.0f64, 0.0f64);
        let t0 = rig.time_s();
        let n = (s.path.duration_s() * 100.0) as usize;
        for k in 0..=n { let t = k as f64 / 100.0; let mut sp = rigsim::RigSetpoint { mode: 0, slip_angle_deg: s.path.at(t), fz_n: s.fz_n, pressure_pa: s.pressure_pa, speed_mps: s.speed_mps, ..Default::default() }; sp.camber_deg = 0.0; rig.apply_setpoint(&sp).unwrap(); rig.run_until(t0 + t + 0.01, &mut |_| {}); let tr = rig.truth(); gmin = gmin.min(tr.grip_factor); tmax = tmax.max(tr.grip_temp_c); }
        println!("{:?}: min grip factor {gmin:.3}, max grip temp {tmax:.1}", kind);
    }
}
