//! Terrain edits from outside (an edit file's line, an Object State PDU): any bytes give an
//! edit the layer applies whole or an error, never a panic; an applied edit's change is finite
//! everywhere and healing it gives the ground back.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let grid = cig_terrain::GeoGrid {
        south_lat_deg: 36.0,
        west_lon_deg: -121.0,
        dlat_deg: 1.0 / 3600.0,
        dlon_deg: 1.0 / 3600.0,
        rows: 257,
        cols: 257,
    };
    let mut edits = Vec::new();
    if let Ok(edit) = serde_json::from_slice::<cig_terrain::TerrainEdit>(data) {
        edits.push(edit);
    }
    for pdu in cig_dis::decode_datagram(data).into_iter().flatten() {
        if let Some(edit) = cig_ig::terrain_edits::edit_of_pdu(&pdu.message, 0.0) {
            edits.push(edit);
        }
    }
    for edit in edits {
        let mut layer = cig_terrain::EditLayer::new(grid, 64);
        let id = edit.id();
        if layer.apply(edit).is_ok() {
            for k in 0..64 {
                let f = f64::from(k) / 64.0;
                let d = layer.delta_m(36.0 + f * 0.07, -121.0 + (1.0 - f) * 0.07);
                assert!(d.is_finite());
            }
            layer.remove(id).expect("an applied edit heals");
            assert_eq!(layer.cells().count(), 0);
        }
    }
});
