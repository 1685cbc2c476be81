//! Track geometry (being written).
