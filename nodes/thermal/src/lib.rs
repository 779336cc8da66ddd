//! thermal: the thermal-gate node (pure core + DDS shell).
