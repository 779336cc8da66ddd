//! What each channel name means: the TTC names (`SA`, `FZ`, `SL`, …) and the TYDEX names
//! (`SLIPANGL`, `FZW`, `LONGSLIP`, …), their quantity, the unit a TTC file uses when it does not
//! say (MATLAB files carry no units), and whether the SAE → ISO-W change flips their sign.

use serde::Serialize;

use crate::units::Quantity;

/// The role a channel plays for the fitter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub enum Role {
    /// Elapsed time (TTC `ET`, TYDEX `RUNTIME`).
    Time,
    /// Road (belt) speed (`V`, `TRAJVELW`).
    RoadSpeed,
    /// Wheel rotational speed (`N`, `ROTSPEED`).
    WheelSpeed,
    /// Slip angle (`SA`, `SLIPANGL`).
    SlipAngle,
    /// Inclination (camber) angle (`IA`, `INCLANGL`).
    Inclination,
    /// Loaded radius (`RL`, `DSTWOWHC`).
    LoadedRadius,
    /// Effective rolling radius computed by the rig (`RE`); shown, not used.
    EffectiveRadius,
    /// Inflation pressure (`P`, `INFLPRES`).
    Pressure,
    /// Longitudinal force.
    Fx,
    /// Lateral force.
    Fy,
    /// Vertical force (load).
    Fz,
    /// Overturning moment.
    Mx,
    /// Rolling resistance moment.
    My,
    /// Aligning moment.
    Mz,
    /// Slip ratio from the loaded radius (TTC `SL`; TYDEX `LONGSLIP`): the slip ratio to use.
    SlipRatio,
    /// Slip ratio from the effective radius (TTC `SR`): used only when there is no `SL`, and
    /// never where the wheel is free rolling.
    SlipRatioEffective,
    /// Tread surface temperature, inner.
    TreadTempInner,
    /// Tread surface temperature, centre.
    TreadTempCentre,
    /// Tread surface temperature, outer.
    TreadTempOuter,
    /// Road surface temperature.
    RoadTemp,
    /// Ambient temperature (shown, checked for °F labelled °C).
    AmbientTemp,
    /// Normalised forces FX/FZ, FY/FZ (shown, not used: recomputed from the forces).
    Normalised,
    /// Distance rolled (TYDEX `LONGDISP`).
    Distance,
}

impl Role {
    /// What the channel measures.
    pub fn quantity(self) -> Quantity {
        use Role::*;
        match self {
            Time => Quantity::Time,
            RoadSpeed => Quantity::Speed,
            WheelSpeed => Quantity::AngularSpeed,
            SlipAngle | Inclination => Quantity::Angle,
            LoadedRadius | EffectiveRadius | Distance => Quantity::Length,
            Pressure => Quantity::Pressure,
            Fx | Fy | Fz => Quantity::Force,
            Mx | My | Mz => Quantity::Moment,
            SlipRatio | SlipRatioEffective | Normalised => Quantity::Ratio,
            TreadTempInner | TreadTempCentre | TreadTempOuter | RoadTemp | AmbientTemp => Quantity::Temperature,
        }
    }

    /// The unit a TTC file means when it writes none (the Calspan conventions).
    pub fn ttc_unit(self) -> &'static str {
        match self.quantity() {
            Quantity::Time => "s",
            Quantity::Speed => "kph",
            Quantity::AngularSpeed => "rpm",
            Quantity::Angle => "deg",
            Quantity::Length => "cm",
            Quantity::Pressure => "kPa",
            Quantity::Force => "N",
            Quantity::Moment => "N-m",
            Quantity::Ratio => "none",
            Quantity::Temperature => "degC",
        }
    }

    /// SAE → ISO-W flips FY, FZ, the slip angle, MY and MZ; FX, MX, slip ratio and inclination
    /// keep their sign (the SAE frame is the ISO frame turned 180° about x).
    pub fn flips_sae_to_iso(self) -> bool {
        matches!(self, Role::Fy | Role::Fz | Role::SlipAngle | Role::My | Role::Mz)
    }

    /// The channels the fitter cannot do without.
    pub fn required(self) -> bool {
        matches!(self, Role::Fz | Role::SlipAngle)
    }

    /// The ISO-W / TYDEX name the value ends up as (for the inspection table).
    pub fn tydex_name(self) -> &'static str {
        use Role::*;
        match self {
            Time => "RUNTIME",
            RoadSpeed => "TRAJVELW",
            WheelSpeed => "ROTSPEED",
            SlipAngle => "SLIPANGL",
            Inclination => "INCLANGL",
            LoadedRadius => "DSTWOWHC",
            EffectiveRadius => "not used (rig-computed)",
            Pressure => "INFLPRES",
            Fx => "FX",
            Fy => "FYW",
            Fz => "FZW",
            Mx => "MXW",
            My => "MYW",
            Mz => "MZW",
            SlipRatio => "LONGSLIP",
            SlipRatioEffective => "LONGSLIP (from SR)",
            TreadTempInner => "TRDTEMPI",
            TreadTempCentre => "TRDTEMPC",
            TreadTempOuter => "TRDTEMPO",
            RoadTemp => "road temperature",
            AmbientTemp => "ambient (checked, not fitted)",
            Normalised => "not used (recomputed)",
            Distance => "LONGDISP",
        }
    }
}

/// The role of a channel name, TTC or TYDEX (ASCII case ignored); `None` for channels the
/// fitter does not use.
pub fn role_of(name: &str) -> Option<Role> {
    use Role::*;
    Some(match name.trim().to_ascii_uppercase().as_str() {
        "ET" | "RUNTIME" | "TIME" => Time,
        "V" | "TRAJVELW" | "VX" => RoadSpeed,
        "N" | "ROTSPEED" => WheelSpeed,
        "SA" | "SLIPANGL" => SlipAngle,
        "IA" | "INCLANGL" => Inclination,
        "RL" | "DSTWOWHC" => LoadedRadius,
        "RE" | "RADEFFEC" => EffectiveRadius,
        "P" | "INFLPRES" => Pressure,
        "FX" | "FXW" => Fx,
        "FY" | "FYW" => Fy,
        "FZ" | "FZW" => Fz,
        "MX" | "MXW" => Mx,
        "MY" | "MYW" => My,
        "MZ" | "MZW" => Mz,
        "SL" | "LONGSLIP" => SlipRatio,
        "SR" => SlipRatioEffective,
        "TSTI" | "TRDTEMPI" => TreadTempInner,
        "TSTC" | "TRDTEMPC" => TreadTempCentre,
        "TSTO" | "TRDTEMPO" => TreadTempOuter,
        "RST" | "ROADTEMP" | "TRCKTEMP" => RoadTemp,
        "AMBTMP" | "AMBTEMP" => AmbientTemp,
        "NFX" | "NFY" => Normalised,
        "LONGDISP" => Distance,
        _ => return None,
    })
}
