//! Orthoimage reader: any file gives an image source (whose first rows read or fail with an
//! error) or an error, never a panic. The reader opens paths, so each input is written to a
//! scratch file first.
#![no_main]
use cig_terrain_io::imagery::ImageSource;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("cig-fuzz-imagery-{}.tif", std::process::id()));
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(source) = ImageSource::open(&path) {
        let (_, height) = source.size();
        let _ = source.window(0, height.min(4).saturating_sub(1));
    }
    let _ = std::fs::remove_file(&path);
});
