//! Prints the fault-injection table of the README: every fault of
//! `tests/it/faults/mod.rs` through the sequential engine and the pipeline.
//!
//! `cargo run --release -p ecvo-pipeline --example faults`

#[path = "../tests/it/faults/mod.rs"]
mod faults;

use faults::{Engine, Fault, measure, table};

fn main() {
    let mut reports = Vec::new();
    for fault in Fault::ALL {
        for engine in [Engine::Core, Engine::Pipeline] {
            reports.push(measure(fault, engine));
        }
    }
    print!("{}", table(&reports));
}
