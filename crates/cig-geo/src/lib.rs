//! WGS84 geodesy (being written).
