//! sequencer: the procedure sequencer node (pure core + DDS shell).
