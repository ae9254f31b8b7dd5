//! The ground's shading cost with and without detail and imagery, for tuning the terrain
//! shader (not a timed test: run with `--ignored --nocapture`; the benchmark of record is
//! `cig bench render`).

mod common;

use cig_geo::Geodetic;
use cig_scene::FrameSnapshot;
use common::*;

#[test]
#[ignore = "a measurement for tuning, not a check"]
fn ground_shading_cost() {
    // The hills under imagery (a pattern of 1.9 m texels) where `CIG_COST_IMAGERY` is set.
    let db = if std::env::var_os("CIG_COST_IMAGERY").is_some() {
        database_with_imagery(
            &hills_raster(),
            4,
            |lat, lon| {
                let v = ((lat * 3e4).sin() * (lon * 2e4).cos() * 60.0 + 120.0) as u8;
                [v, v / 2 + 40, 70, 255]
            },
            |k| k.level < 2,
        )
    } else {
        hills()
    };
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let eye = Geodetic::new(36.0, -121.2, 400.0);
    let detailed = FrameSnapshot::new(
        MORNING_UNIX_S,
        vec![view(eye, (30.0, -12.0, 0.0), 60.0, (640, 480))],
    );
    let plain = FrameSnapshot {
        ground_detail: false,
        ..detailed.clone()
    };
    render(&mut renderer, &cache, &detailed, false);
    render(&mut renderer, &cache, &plain, false);
    let (mut with, mut without) = (Vec::new(), Vec::new());
    for _ in 0..12 {
        with.push(render(&mut renderer, &cache, &detailed, false).1.gpu_ms);
        without.push(render(&mut renderer, &cache, &plain, false).1.gpu_ms);
    }
    with.sort_by(f64::total_cmp);
    without.sort_by(f64::total_cmp);
    // The least of each: the machine's other work only ever adds time.
    let (a, b) = (with[0], without[0]);
    eprintln!(
        "detailed {a:.1} ms, plain {b:.1} ms, ratio {:.3} (least of 12 each)",
        a / b
    );
}
