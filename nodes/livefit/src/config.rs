//! The live fit's settings.

use mffit::FitOptions;
use serde::Deserialize;

/// Settings of the live fit (a launch file's `[nodes.fit]` keys, or `tyrerig run`'s flags).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LiveFitConfig {
    /// Largest number of points a stage fits (evenly decimated beyond), as `tyrerig fit
    /// --max-points`; the same default, so the live and offline fits see the same points.
    pub max_points: usize,
    /// Worker threads of an update (numeric Jacobian columns); 0 = all cores.
    pub threads: usize,
    /// Iteration limit per optimiser step of the final update (as the offline fit's).
    pub max_iterations: usize,
    /// Iteration limit per optimiser step of the updates after each sweep. Warm-started, each
    /// update continues where the last stopped, so the model converges over the updates while
    /// one update stays within the time between two sweeps.
    pub update_max_iterations: usize,
    /// Nominal load Fz0 of the run [N] (the plan's); `None` = estimated from the data, as the
    /// offline fit does without log metadata.
    pub fz0_n: Option<f64>,
    /// Nominal pressure of the envelope grid [Pa]; `None` = the fit's NOMPRES at the first update.
    pub p0_pa: Option<f64>,
    /// Fit the graph sweeps too (as `tyrerig fit --include-graph-sweeps`).
    pub include_graph_sweeps: bool,
}

impl Default for LiveFitConfig {
    fn default() -> Self {
        let offline = FitOptions::default();
        LiveFitConfig {
            max_points: offline.max_points,
            threads: 0,
            max_iterations: offline.max_iterations,
            update_max_iterations: 10,
            fz0_n: None,
            p0_pa: None,
            include_graph_sweeps: false,
        }
    }
}

impl LiveFitConfig {
    /// The options of an update after a sweep (`final_update`: at the procedure's end): the
    /// offline fit's, without cross-validation (the k-fold refits every stage K times; the live
    /// model's figure of merit is its uncertainty instead).
    pub fn update_options(&self, final_update: bool) -> FitOptions {
        let mut o = self.fit_options();
        if !final_update {
            o.max_iterations = self.update_max_iterations.max(1);
            o.restarts = false;
        }
        o
    }

    /// The offline fit's options with these settings, without cross-validation.
    pub fn fit_options(&self) -> FitOptions {
        let mut o = FitOptions {
            max_points: self.max_points,
            max_iterations: self.max_iterations,
            fnomin_n: self.fz0_n,
            include_graph_sweeps: self.include_graph_sweeps,
            folds: 0,
            ..FitOptions::default()
        };
        if self.threads > 0 {
            o.threads = self.threads;
        }
        o
    }
}
