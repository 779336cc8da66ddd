//! node_runtime: the one place besides node shells that knows DDS.
