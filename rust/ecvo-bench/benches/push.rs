//! The cost `push` adds per frame to tell a repeated frame: the 64-bit content hash
//! of both planes, against copying the same frame into a pooled buffer (which
//! `push` does anyway), measured in the same run.
//!
//! `cargo bench -p ecvo-bench --bench push`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn benches(c: &mut Criterion) {
    for (name, w, h) in [
        ("320x180", 320, 180),
        ("320x240", 320, 240),
        ("640x480", 640, 480),
    ] {
        let n = w * h;
        let intensity: Vec<u8> = (0..n).map(|i| (i * 7 % 251) as u8).collect();
        let depth: Vec<u16> = (0..n).map(|i| (500 + i % 3000) as u16).collect();
        let mut gi = vec![0u8; n];
        let mut gd = vec![0u16; n];
        let mut g = c.benchmark_group("push");
        g.bench_with_input(BenchmarkId::new("hash", name), &(), |b, _| {
            b.iter(|| ecvo_pipeline::frame_hash(black_box(&intensity), black_box(&depth)))
        });
        g.bench_with_input(BenchmarkId::new("copy", name), &(), |b, _| {
            b.iter(|| {
                gi.copy_from_slice(black_box(&intensity));
                gd.copy_from_slice(black_box(&depth));
                black_box((&gi, &gd));
            })
        });
        g.finish();
    }
}

criterion_group!(push, benches);
criterion_main!(push);
