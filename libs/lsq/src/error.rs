//! Errors for invalid problems and options (never for a fit that merely fails to converge:
//! that is a [`crate::Termination`] in the report).

/// Why a solve or a Jacobian check could not start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LsqError {
    /// The parameter vector is empty.
    #[error("no parameters to fit")]
    NoParameters,
    /// Fewer residuals than parameters: the problem is underdetermined.
    #[error("{residuals} residuals cannot determine {params} parameters")]
    Underdetermined {
        /// Number of residuals.
        residuals: usize,
        /// Number of parameters.
        params: usize,
    },
    /// A bound vector's length differs from the number of parameters.
    #[error("{which} bounds have {len} entries, expected {params}")]
    BoundsLength {
        /// `"lower"` or `"upper"`.
        which: &'static str,
        /// Its length.
        len: usize,
        /// Number of parameters.
        params: usize,
    },
    /// A lower bound above its upper bound, or a NaN bound.
    #[error("parameter {index}: bounds [{lower}, {upper}] are empty or NaN")]
    InvalidBounds {
        /// Parameter index.
        index: usize,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// A starting parameter is NaN or infinite.
    #[error("starting parameter {index} is {value}, expected a finite value")]
    NonFiniteStart {
        /// Parameter index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// The residuals at the (projected) starting point are not all finite.
    #[error("residual {index} is {value} at the starting point")]
    NonFiniteResiduals {
        /// Residual index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// An option is out of range.
    #[error("option `{name}` = {value} is invalid: expected {expected}")]
    InvalidOption {
        /// The option's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must satisfy.
        expected: &'static str,
    },
    /// The problem's `residuals` wrote a vector of the wrong length (it must not resize `r`).
    #[error("the problem returned {len} residuals, declared {expected}")]
    ResidualLength {
        /// Length found.
        len: usize,
        /// `num_residuals()`.
        expected: usize,
    },
    /// `check_jacobian` needs an analytic Jacobian, and the problem has none.
    #[error("the problem has no analytic Jacobian to check")]
    NoAnalyticJacobian,
}
