//! ETRTO load index → load capacity, and the GS2MF nominal load Fz0 derived from it.

/// Gravitational acceleration used by the thesis to turn kg of load capacity into newtons.
pub const G_MPS2: f64 = 9.81;

/// Fz0 is 65 % of the ETRTO capacity (§3.3 of the thesis): a typical static corner load.
pub const FZ0_FRACTION_OF_CAPACITY: f64 = 0.65;

/// The thesis's tyre's load index (Fz0 = 6,759 N): the graph sweeps' absolute loads are its.
pub const THESIS_LOAD_INDEX: u32 = 110;

/// Lowest load index in [`LOAD_CAPACITY_KG`].
pub const LOAD_INDEX_MIN: u32 = 60;

/// ETRTO load capacity in kg for load indices 60..=130 (index `li - 60`).
pub const LOAD_CAPACITY_KG: [f64; 71] = [
    250.0, 257.0, 265.0, 272.0, 280.0, 290.0, 300.0, 307.0, 315.0, 325.0, // 60-69
    335.0, 345.0, 355.0, 365.0, 375.0, 387.0, 400.0, 412.0, 425.0, 437.0, // 70-79
    450.0, 462.0, 475.0, 487.0, 500.0, 515.0, 530.0, 545.0, 560.0, 580.0, // 80-89
    600.0, 615.0, 630.0, 650.0, 670.0, 690.0, 710.0, 730.0, 750.0, 775.0, // 90-99
    800.0, 825.0, 850.0, 875.0, 900.0, 925.0, 950.0, 975.0, 1000.0, 1030.0, // 100-109
    1060.0, 1090.0, 1120.0, 1150.0, 1180.0, 1215.0, 1250.0, 1285.0, 1320.0, 1360.0, // 110-119
    1400.0, 1450.0, 1500.0, 1550.0, 1600.0, 1650.0, 1700.0, 1750.0, 1800.0, 1850.0, // 120-129
    1900.0, // 130
];

/// Highest load index in [`LOAD_CAPACITY_KG`].
pub const LOAD_INDEX_MAX: u32 = LOAD_INDEX_MIN + LOAD_CAPACITY_KG.len() as u32 - 1;

/// A load index outside the table.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("ETRTO load index {load_index} is outside the supported table ({min}..={max})")]
pub struct UnknownLoadIndex {
    /// The index asked for.
    pub load_index: u32,
    /// Lowest supported index.
    pub min: u32,
    /// Highest supported index.
    pub max: u32,
}

/// ETRTO load capacity in kg for `load_index`.
pub fn load_capacity_kg(load_index: u32) -> Result<f64, UnknownLoadIndex> {
    load_index
        .checked_sub(LOAD_INDEX_MIN)
        .and_then(|i| LOAD_CAPACITY_KG.get(i as usize).copied())
        .ok_or(UnknownLoadIndex { load_index, min: LOAD_INDEX_MIN, max: LOAD_INDEX_MAX })
}

/// GS2MF nominal load Fz0 = 0.65 × capacity × 9.81 N (LI 110 → 6,752 N).
pub fn fz0_n(load_index: u32) -> Result<f64, UnknownLoadIndex> {
    Ok(FZ0_FRACTION_OF_CAPACITY * load_capacity_kg(load_index)? * G_MPS2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thesis_tyre_li110() {
        assert_eq!(load_capacity_kg(110).unwrap(), 1060.0);
        // The thesis quotes 10,388 N and 6,752 N: it multiplied by 9.8, not 9.81. We keep the
        // documented formula (× 9.81); the difference is 0.1 %.
        let fz0 = fz0_n(110).unwrap();
        assert!((fz0 - 6759.09).abs() < 0.1, "{fz0}");
        assert!((fz0 - 6752.0).abs() / 6752.0 < 0.002);
    }

    #[test]
    fn table_ends_and_monotone() {
        assert_eq!(load_capacity_kg(60).unwrap(), 250.0);
        assert_eq!(load_capacity_kg(130).unwrap(), 1900.0);
        assert_eq!(LOAD_INDEX_MAX, 130);
        for w in LOAD_CAPACITY_KG.windows(2) {
            assert!(w[1] > w[0]);
        }
        assert!(load_capacity_kg(59).is_err());
        assert!(load_capacity_kg(131).is_err());
        assert!(load_capacity_kg(0).is_err());
    }
}
