//! `--levels` parsing (`ecvo_core::config::parse_levels`, used by `ecvo run --levels`).
#![no_main]

use ecvo_core::config::parse_levels;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(levels) = parse_levels(text) {
        for l in &levels {
            assert!(l.max_distance_m.is_finite() && l.max_distance_m >= 0.0);
            assert!(l.max_angle_deg.is_finite() && (0.0..180.0).contains(&l.max_angle_deg));
        }
        // Written back the way `ecvo run` writes them, they parse to the same levels.
        let text: Vec<String> = levels
            .iter()
            .map(|l| format!("{:?}m:{:?}deg", l.max_distance_m, l.max_angle_deg))
            .collect();
        let back = parse_levels(&text.join(",")).expect("written levels parse");
        assert_eq!(back.len(), levels.len());
        if levels.is_empty() {
            return;
        }
        for (a, b) in back.iter().zip(&levels) {
            assert_eq!(a.max_distance_m, b.max_distance_m);
            assert_eq!(a.max_angle_deg, b.max_angle_deg);
        }
    }
});
