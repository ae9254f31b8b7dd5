//! Scenario files: any text gives a scenario or a one-line error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match cig_ig::Scenario::from_toml(text) {
        Ok(s) => {
            let _ = cig_ig::ModelTable::from_scenario(&s);
        }
        Err(e) => assert!(!e.to_string().contains('\n'), "one line: {e}"),
    }
});
