//! Synthetic terrain (being written).
