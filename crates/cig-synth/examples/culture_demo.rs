//! Places the culture of the demonstration database (50 km x 50 km at 30 m near Fort Hunter
//! Liggett) with the default rules and prints the time taken, the counts of each kind and the
//! fullest finest tile.
//!
//! `cargo run --release -p cig-synth --example culture_demo [size_km spacing_m seed tile_cells]`

use cig_synth::culture::{place_culture, CultureRules};
use cig_synth::{synthesize_with_features, SynthParams};
use cig_terrain::culture::{bin_placements, MAX_ITEMS_PER_TILE};
use cig_terrain::PyramidLayout;
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
    let tile_cells: u32 = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(128);
    let start = Instant::now();
    let (raster, report, features) = match synthesize_with_features(&params, &mut |_, _| {}) {
        Ok(generated) => generated,
        Err(e) => {
            eprintln!("cannot synthesize: {e}");
            std::process::exit(1);
        }
    };
    println!("synthesized in {:.3} s", start.elapsed().as_secs_f64());
    let start = Instant::now();
    let placed = match place_culture(
        &raster,
        &report,
        &features,
        &CultureRules::default(),
        params.seed,
    ) {
        Ok(placed) => placed,
        Err(e) => {
            eprintln!("cannot place culture: {e}");
            std::process::exit(1);
        }
    };
    println!(
        "placed {} objects in {:.3} s",
        placed.len(),
        start.elapsed().as_secs_f64()
    );
    let start = Instant::now();
    match bin_placements(&PyramidLayout::new(raster.grid, tile_cells), &placed) {
        Ok((tiles, manifest)) => {
            println!(
                "binned into {} tiles of {tile_cells} cells in {:.3} s",
                tiles.len(),
                start.elapsed().as_secs_f64()
            );
            for (kind, n) in &manifest.counts {
                println!("  {kind:<15} {n:>9}");
            }
            println!(
                "trees {}, buildings {}, fullest tile {} objects (at most {MAX_ITEMS_PER_TILE})",
                manifest.trees(),
                manifest.buildings(),
                manifest.max_items_per_tile
            );
        }
        Err(e) => {
            eprintln!("cannot bin: {e}");
            std::process::exit(1);
        }
    }
}
