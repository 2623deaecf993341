//! The pure-Rust argument validation of `nativeInit` (`ecvo_jni::InitArgs::build`):
//! every field arbitrary, including NaN, infinities and negative sizes.
#![no_main]

use ecvo_jni::{Confidence, DepthFormat, InitArgs};
use libfuzzer_sys::arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;

fn args(u: &mut Unstructured<'_>) -> Result<InitArgs> {
    // Sizes mostly near the valid range, sometimes anything.
    let size = |u: &mut Unstructured<'_>| -> Result<i32> {
        Ok(if u.arbitrary::<bool>()? {
            u.int_in_range(-2..=9000)?
        } else {
            u.arbitrary()?
        })
    };
    Ok(InitArgs {
        width: size(u)?,
        height: size(u)?,
        fx: u.arbitrary()?,
        fy: u.arbitrary()?,
        cx: u.arbitrary()?,
        cy: u.arbitrary()?,
        depth_format: u.int_in_range(-1..=3)?,
        depth_scale: u.arbitrary()?,
        min_confidence: u.int_in_range(-2..=9)?,
        preset: u.int_in_range(-1..=2)?,
        mode: u.int_in_range(-1..=3)?,
        live: u.arbitrary()?,
        threads: u.int_in_range(-1..=300)?,
        point_cloud: u.arbitrary()?,
    })
}

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let Ok(a) = args(&mut u) else {
        return;
    };
    match a.build() {
        Ok((config, options, format, min_conf)) => {
            // Whatever the validation lets through is a configuration the engine and
            // the pipeline take.
            assert!(config.validate().is_ok());
            assert_eq!(config.camera.width as i64, i64::from(a.width));
            assert_eq!(config.camera.height as i64, i64::from(a.height));
            assert!((1..=256).contains(&options.threads));
            match (format, min_conf) {
                (DepthFormat::Depth16, Confidence::Documented(level)) => {
                    assert_eq!(i32::from(level), a.min_confidence);
                    assert!(level <= 7);
                }
                (DepthFormat::Depth16, Confidence::Auto) => assert_eq!(a.min_confidence, -1),
                (_, rule) => assert_eq!(rule, Confidence::Documented(0)),
            }
            assert_eq!(DepthFormat::from_code(a.depth_format), Some(format));
            assert!(config.camera.depth_scale.is_finite() && config.camera.depth_scale > 0.0);
        }
        Err(ecvo_jni::Failure::IllegalArgument(msg)) => assert!(!msg.is_empty()),
        Err(other) => panic!("init arguments failed with {other:?}, not IllegalArgument"),
    }
});
