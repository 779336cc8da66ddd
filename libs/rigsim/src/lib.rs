//! rigsim: the virtual flat-track rig simulation core (pure, deterministic, time as data).
