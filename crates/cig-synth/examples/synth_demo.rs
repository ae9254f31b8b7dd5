//! Generates the demonstration database (50 km x 50 km at 30 m near Fort Hunter Liggett) and
//! prints the time taken and a summary.
//!
//! `cargo run --release -p cig-synth --example synth_demo [size_km spacing_m seed]`
//!
//! It also prints a hash of the raster, to compare machines (the unit test
//! `golden_hash_of_a_small_case` pins the hash of `3 60 7`).

use cig_synth::{synthesize_with_report, SynthParams};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut params = SynthParams::demo();
    if let Some(v) = args.first().and_then(|a| a.parse().ok()) {
        params.size_km = v;
    }
    if let Some(v) = args.get(1).and_then(|a| a.parse().ok()) {
        params.spacing_m = v;
    }
    if let Some(v) = args.get(2).and_then(|a| a.parse().ok()) {
        params.seed = v;
    }
    let start = Instant::now();
    let mut last = String::new();
    let mut stage_start = Instant::now();
    let mut progress = |stage: &str, frac: f32| {
        if stage != last {
            if !last.is_empty() {
                println!("  {last:<10} {:6.3} s", stage_start.elapsed().as_secs_f64());
            }
            last = stage.to_string();
            stage_start = Instant::now();
        }
        let _ = frac;
    };
    match synthesize_with_report(&params, &mut progress) {
        Ok((raster, report)) => {
            println!("  {last:<10} {:6.3} s", stage_start.elapsed().as_secs_f64());
            println!("{params:?}");
            println!("generated in {:.3} s", start.elapsed().as_secs_f64());
            println!("{report}");
            // FNV-1a of the elevation bits and material bytes: compare across machines.
            let mut hash = 0xcbf2_9ce4_8422_2325u64;
            let materials = raster.material.as_deref().unwrap_or(&[]);
            for b in raster
                .elevation_m
                .iter()
                .flat_map(|v| v.to_bits().to_le_bytes())
                .chain(materials.iter().map(|m| m.to_byte()))
            {
                hash ^= u64::from(b);
                hash = hash.wrapping_mul(0x0000_0100_0000_01B3);
            }
            println!("raster hash {hash:#018x}");
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
