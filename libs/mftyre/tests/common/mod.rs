//! Shared helpers for the integration tests: fixture paths and a tiny CSV reader.

#![allow(dead_code)] // Each test binary uses a different subset.

use std::path::PathBuf;

use mftyre::{MfInput, MfOutput, TyreParams};

/// `tests/fixtures/mfeval` at the workspace root.
pub fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/mfeval")
}

/// `launch-config/tyres` at the workspace root.
pub fn tyres_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/tyres")
}

/// The project's default virtual tyre (the file MFeval's reference was computed for).
pub fn sample_tyre() -> TyreParams {
    let path = tyres_dir().join("MagicFormula61_Paramerters.tir");
    match TyreParams::read_tir(&path) {
        Ok(p) => p,
        Err(e) => panic!("{e}"),
    }
}

/// A numeric CSV: header names and rows.
pub struct Table {
    pub header: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    pub fn col(&self, name: &str) -> usize {
        self.header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name}"))
    }
}

pub fn read_table(name: &str) -> Table {
    let path = fixtures().join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines.next().expect("header").split(',').map(|s| s.trim().to_owned()).collect();
    let rows = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            l.split(',')
                .map(|v| {
                    let v = v.trim();
                    match v {
                        "Inf" | "inf" => f64::INFINITY,
                        "-Inf" | "-inf" => f64::NEG_INFINITY,
                        "NaN" | "nan" | "" => f64::NAN,
                        _ => v.parse().unwrap_or_else(|_| panic!("bad number {v} in {name}")),
                    }
                })
                .collect()
        })
        .collect();
    Table { header, rows }
}

pub fn inputs_of(t: &Table) -> Vec<MfInput> {
    let c = |n| t.col(n);
    let (fz, k, a, g, ph, vx, p, w) =
        (c("Fz"), c("kappa"), c("alpha"), c("gamma"), c("phit"), c("Vx"), c("P"), c("omega"));
    t.rows
        .iter()
        .map(|r| MfInput {
            fz_n: r[fz],
            kappa: r[k],
            alpha_rad: r[a],
            gamma_rad: r[g],
            phit_per_m: r[ph],
            vx_mps: r[vx],
            p_pa: r[p],
            omega_radps: r[w],
        })
        .collect()
}

/// The MFeval output column named `name` of an [`MfOutput`].
pub fn column(o: &MfOutput, name: &str) -> f64 {
    match name {
        "Fx" => o.fx_n,
        "Fy" => o.fy_n,
        "Fz" => o.fz_n,
        "Mx" => o.mx_nm,
        "My" => o.my_nm,
        "Mz" => o.mz_nm,
        "kappa" => o.kappa,
        "alpha" => o.alpha_rad,
        "gamma" => o.gamma_rad,
        "phit" => o.phit_per_m,
        "Vx" => o.vx_mps,
        "P" => o.p_pa,
        "Re" => o.re_m,
        "rho" => o.rho_m,
        "2a" => o.contact_length_m,
        "t" => o.trail_m,
        "mux" => o.mux,
        "muy" => o.muy,
        "omega" => o.omega_radps,
        "Rl" => o.rl_m,
        "2b" => o.contact_width_m,
        "Mzr" => o.mzr_nm,
        "Cx" => o.cx_npm,
        "Cy" => o.cy_npm,
        "Cz" => o.cz_npm,
        "Kya" => o.kya_nprad,
        "sigmax" => o.sigmax_m,
        "sigmay" => o.sigmay_m,
        "Kxk" => o.kxk_n,
        other => panic!("unknown column {other}"),
    }
}
