//! Fidelity selection (in progress).
