//! The IMU's text inputs (issue 47): `imu.txt` lines and the `imu` object of
//! `camera.json`, and the engine taking what the reader accepts. The first byte picks
//! the parser.
#![no_main]

use std::path::Path;

use ecvo_io::imu::{parse_imu, parse_imu_calibration};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&which, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let path = Path::new("fuzz.txt");
    if which % 2 == 0 {
        if let Ok(samples) = parse_imu(text, path) {
            for w in samples.windows(2) {
                assert!(w[0].t < w[1].t);
            }
            let gyro: Vec<_> = samples.iter().map(|s| s.gyro()).collect();
            let mut g = ecvo_core::imu::Gyro::new(ecvo_core::ImuCalibration::default());
            let mut c = ecvo_core::imu::ImuCounters::default();
            // What the reader accepts, the engine takes whole, and integrates.
            g.push(&gyro, &mut c).expect("finite samples are taken");
            assert_eq!(c.samples, gyro.len() as u64);
            if let (Some(a), Some(b)) = (gyro.first(), gyro.last())
                && let Ok(q) = g.rotation_between(a.t, b.t)
            {
                assert!(q.coords.iter().all(|x| x.is_finite()));
            }
        }
    } else if let Ok(Some(c)) = parse_imu_calibration(text, path) {
        assert!(c.validate().is_ok());
    }
});
