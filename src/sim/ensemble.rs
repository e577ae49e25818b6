//! Ensembles (in progress).
