//! The criterion benches of ecvo, apart from the crates they measure so that the test
//! build (`scripts/test.sh`, which excludes this crate) does not compile criterion and
//! its dependencies. The library is empty; the benches are in `benches/`:
//!
//! ```text
//! cargo bench -p ecvo-bench --bench stages   # ecvo-core: the filter stage and MOTION
//! cargo bench -p ecvo-bench --bench push     # ecvo-pipeline: push's frame hash
//! ```
