//! The EGM96 geoid: undulation N of mean sea level above the WGS84 ellipsoid.
//!
//! Algorithm: spherical-harmonic synthesis of the EGM96 potential model to
//! degree and order 360 plus Rapp's height-anomaly-to-undulation correction
//! series and the -0.53 m zero-degree term that refers the result to WGS84;
//! the NGA program F477 (R. H. Rapp, "Use of potential coefficient models for
//! geoid undulation determination using a spherical harmonic representation
//! of the height anomaly/geoid undulation difference", *J. Geodesy* 71, 1997;
//! F. G. Lemoine et al., *The development of the joint NASA GSFC and NIMA
//! geopotential model EGM96*, NASA/TP-1998-206861), as ported to Rust by the
//! crates.io crate `egm96` (function `egm96_compute_altitude_offset`, built
//! without default features so that it computes from the coefficients it
//! ships and never downloads a grid).
//!
//! Limits:
//! - Accuracy is that of EGM96 itself, about 0.5–1 m (worse in the
//!   mountains); the synthesis reproduces NGA's published test values to a
//!   few millimetres (see the tests).
//! - **Cost: about 1 ms of CPU per call** (0.85–1.3 ms measured; see
//!   [`egm96_undulation_m`]), because every call recomputes about 65 000
//!   normalised Legendre functions and sums as many harmonic terms. Sample
//!   it on a coarse grid and interpolate; never call it per vertex or per
//!   pixel. Bilinear
//!   interpolation from a 0.25-degree grid of this function was measured at
//!   0.04 m rms and 0.43 m worst over 400 random points (80 S..80 N), below
//!   EGM96's own error; from a 1-degree grid, 0.39 m rms and 3.9 m worst.
//! - Each calling thread keeps a scratch buffer of about 0.5 MB (a
//!   thread-local inside `egm96`), and the coefficient table adds about 2 MB
//!   to the binary.

/// EGM96 geoid undulation N (geoid height above the WGS84 ellipsoid) in
/// metres, so that ellipsoidal height = orthometric (MSL) height + N.
///
/// N ranges over about -107 m (south of India) to +85 m (New Guinea).
/// Thread-safe (each thread uses its own scratch buffer).
/// Latitudes outside `[-90, 90]` are clamped and longitudes are taken modulo
/// 360; NaN in gives NaN out.
///
/// Cost: about 1 ms per call (0.85–1.3 ms measured on one core of an x86-64
/// build machine, optimised build, 2000 scattered points; the thread's first
/// call also allocates its scratch buffer). A 1-degree global grid is 65 000
/// calls, about a minute; a 0.25-degree grid over a 2-degree database tile is
/// 81 calls, under 0.1 s. Callers should sample on a coarse grid and
/// interpolate.
pub fn egm96_undulation_m(lat_deg: f64, lon_deg: f64) -> f64 {
    egm96::egm96_compute_altitude_offset(lat_deg, lon_deg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nga_published_test_values() {
        // NGA's EGM96 readme (earth-info.nga.mil, egm96 "readme.txt" /
        // OUTINTPT.DAT): geoid heights at six test points, interpolated from
        // the 15-minute grid; the harmonic synthesis (F477) agrees to a few
        // millimetres. Longitudes in 0..360 as published.
        let cases = [
            (38.628_155_0, 269.779_155_0, -31.628),
            (-14.621_217_0, 305.021_114_0, -2.969),
            (46.874_319_0, 102.448_729_0, -43.575),
            (-23.617_446_0, 133.874_712_0, 15.871),
            (38.625_473_0, 359.999_500_0, 50.066),
            (-0.466_744_0, 0.002_300_0, 17.329),
        ];
        for (lat, lon, n_m) in cases {
            let got = egm96_undulation_m(lat, lon);
            assert!((got - n_m).abs() < 0.01, "({lat}, {lon}): {got} vs {n_m}");
            // Longitude in -180..180 gives the same answer.
            let got_w = egm96_undulation_m(lat, lon - 360.0);
            assert!(
                (got_w - got).abs() < 1e-6,
                "({lat}, {lon}): {got_w} vs {got}"
            );
        }
    }

    #[test]
    fn nga_grid_pole_values() {
        // NGA WW15MGH.GRD (the EGM96 15-minute grid): its first row (90 N) is
        // 13.606 m and its last row (90 S) -29.534 m at every longitude.
        for lon in [0.0, 77.0, -140.0] {
            let n = egm96_undulation_m(90.0, lon);
            assert!((n - 13.606).abs() < 0.01, "{n}");
            let s = egm96_undulation_m(-90.0, lon);
            assert!((s - -29.534).abs() < 0.01, "{s}");
        }
    }

    #[test]
    fn brief_reference_values_and_sign() {
        // Central California coast: N is about -33 m (geoid below the
        // ellipsoid, so ellipsoidal height < MSL height).
        let n = egm96_undulation_m(36.0, -121.0);
        assert!((n - -33.0).abs() < 1.0, "{n}");
        // The origin of latitude and longitude: +17.16 m (GeographicLib
        // GeoidEval with the egm96-5 grid).
        let n = egm96_undulation_m(0.0, 0.0);
        assert!((n - 17.16).abs() < 0.1, "{n}");
    }

    #[test]
    fn extremes_and_edges() {
        // The EGM96 minimum south of Sri Lanka, about -107 m near (4.7 N, 78.8 E).
        let n = egm96_undulation_m(4.7, 78.8);
        assert!((n - -107.0).abs() < 0.5, "{n}");
        for (lat, lon) in [(90.0, 0.0), (-90.0, 0.0), (0.0, 180.0), (0.0, -180.0)] {
            assert!(egm96_undulation_m(lat, lon).is_finite(), "({lat}, {lon})");
        }
        // All longitudes meet at a pole.
        let a = egm96_undulation_m(90.0, 0.0);
        let b = egm96_undulation_m(90.0, 123.0);
        assert!((a - b).abs() < 1e-6, "{a} vs {b}");
        assert!(egm96_undulation_m(f64::NAN, 0.0).is_nan());
    }
}
