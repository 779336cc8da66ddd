//! lsq: bounded nonlinear least squares (Levenberg–Marquardt) on nalgebra.
