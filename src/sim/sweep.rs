//! Parameter sweep (in progress).
