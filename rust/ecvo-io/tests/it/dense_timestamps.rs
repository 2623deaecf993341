//! Regression test: image lists or trajectories with thousands of timestamps within
//! the association window used to make `associate_stamps` collect every pair within
//! `max_dt` (quadratic: 20,000 x 20,000 timestamps 1 µs apart are 4e8 candidates,
//! about 9.6 GB) before pairing them. Now each timestamp considers a bounded number of
//! neighbours.

use std::time::Instant;

use ecvo_io::associate_stamps;

#[test]
fn dense_timestamps_pair_in_linear_memory() {
    let n = 20_000;
    let a: Vec<f64> = (0..n).map(|i| 1.0 + i as f64 * 1e-6).collect();
    let b = a.clone();
    let t = Instant::now();
    let pairs = associate_stamps(&a, &b, 0.02);
    assert!(t.elapsed().as_secs_f64() < 10.0, "{:?}", t.elapsed());
    assert_eq!(pairs.len(), n);
    assert!(pairs.iter().all(|&(i, j)| i == j));
}

#[test]
fn dense_but_offset_timestamps_still_pair_nearest_first() {
    // Every second timestamp's nearest partner is 0.4 µs away, the others' further.
    let a: Vec<f64> = (0..5000).map(|i| i as f64 * 1e-6).collect();
    let b: Vec<f64> = (0..5000).map(|i| i as f64 * 1e-6 + 4e-7).collect();
    let pairs = associate_stamps(&a, &b, 0.02);
    assert_eq!(pairs.len(), 5000);
    for &(i, j) in &pairs {
        assert!((a[i] - b[j]).abs() < 0.02);
    }
    // One-to-one.
    let mut seen = vec![false; b.len()];
    for &(_, j) in &pairs {
        assert!(!seen[j]);
        seen[j] = true;
    }
    assert_eq!(pairs[0], (0, 0));
}
