//! The geometry stage's cloud: the points of the reference frames in world
//! coordinates, optionally thinned by a voxel grid, with a hard cap on its size.
//!
//! The cloud is append-only (a voxel keeps the first point that lands in it), so any
//! prefix of it is a consistent snapshot and a renderer can copy only what is new.
//! Its storage is reserved up front for `max_points` points, so it never reallocates.

use std::collections::HashSet;
use std::hash::{BuildHasherDefault, DefaultHasher};

use ecvo_core::{Pose, PreparedFrame};

/// Settings of the geometry stage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeometryOptions {
    /// Keep one point per cube of this side (metres); `None` keeps every point.
    pub voxel_size_m: Option<f32>,
    /// Hard cap on the points kept; points beyond it are discarded. Storage for this
    /// many points (and voxels) is reserved when the pipeline starts.
    pub max_points: usize,
    /// Take every `point_stride`-th pixel of a reference frame in each direction.
    pub point_stride: usize,
}

impl Default for GeometryOptions {
    /// 1 cm voxels, at most 500 000 points (about 14 MB plus the voxel set), every
    /// 2nd pixel.
    fn default() -> Self {
        GeometryOptions {
            voxel_size_m: Some(0.01),
            max_points: 500_000,
            point_stride: 2,
        }
    }
}

/// One point of the cloud, in world coordinates (the first camera's frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CloudPoint {
    /// Position, metres.
    pub position: [f32; 3],
    /// Unit normal towards the camera that saw it (NaN where unknown).
    pub normal: [f32; 3],
    /// Gray level 0..=255.
    pub intensity: u8,
}

/// The accumulated cloud.
pub(crate) struct Cloud {
    opts: GeometryOptions,
    pub(crate) points: Vec<CloudPoint>,
    /// Fixed-key hashing: std's random `RandomState` would make libecvo_jni import
    /// bionic's `getrandom` (API 28, above minSdk 26; `check-so.sh` rejects it), and
    /// the keys are our own voxel indices, so there is nothing to defend against.
    voxels: HashSet<(i32, i32, i32), BuildHasherDefault<DefaultHasher>>,
    /// Points rejected because the cloud was full.
    pub(crate) discarded: u64,
}

impl Cloud {
    pub(crate) fn new(opts: GeometryOptions) -> Self {
        Cloud {
            opts,
            points: Vec::with_capacity(opts.max_points),
            voxels: if opts.voxel_size_m.is_some() {
                HashSet::with_capacity_and_hasher(opts.max_points, Default::default())
            } else {
                HashSet::default()
            },
            discarded: 0,
        }
    }

    /// Adds already transformed points.
    pub(crate) fn extend(&mut self, staged: &[CloudPoint]) {
        let inv = self.opts.voxel_size_m.map(|v| 1.0 / v);
        for p in staged {
            if self.points.len() >= self.opts.max_points {
                self.discarded += 1;
                continue;
            }
            if let Some(inv) = inv {
                let key = (
                    (p.position[0] * inv).floor() as i32,
                    (p.position[1] * inv).floor() as i32,
                    (p.position[2] * inv).floor() as i32,
                );
                if !self.voxels.insert(key) {
                    continue;
                }
            }
            self.points.push(*p);
        }
    }
}

/// Transforms the points of a reference frame at `pose` into `staged` (cleared
/// first), outside any lock.
pub(crate) fn stage_points(
    frame: &PreparedFrame,
    pose: &Pose,
    stride: usize,
    staged: &mut Vec<CloudPoint>,
) {
    staged.clear();
    let r = pose.rotation.to_rotation_matrix();
    let m = r.matrix();
    let rot: [[f32; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)] as f32));
    let t = pose.translation.vector;
    let t = [t.x as f32, t.y as f32, t.z as f32];
    let apply = |v: [f32; 3]| -> [f32; 3] {
        std::array::from_fn(|i| rot[i][0] * v[0] + rot[i][1] * v[1] + rot[i][2] * v[2])
    };
    frame.for_each_point(stride, |p, n, intensity| {
        let q = apply(p);
        staged.push(CloudPoint {
            position: [q[0] + t[0], q[1] + t[1], q[2] + t[2]],
            normal: apply(n),
            intensity,
        });
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(x: f32) -> CloudPoint {
        CloudPoint {
            position: [x, 0.0, 1.0],
            normal: [0.0, 0.0, -1.0],
            intensity: 7,
        }
    }

    #[test]
    fn voxel_grid_keeps_the_first_point_and_the_cap_holds() {
        let mut c = Cloud::new(GeometryOptions {
            voxel_size_m: Some(0.1),
            max_points: 3,
            point_stride: 1,
        });
        let cap = c.points.capacity();
        c.extend(&[pt(0.01), pt(0.02), pt(0.15), pt(-0.01)]);
        assert_eq!(c.points, vec![pt(0.01), pt(0.15), pt(-0.01)]);
        c.extend(&[pt(0.35), pt(0.55)]);
        assert_eq!(c.points.len(), 3);
        assert_eq!(c.discarded, 2);
        assert_eq!(c.points.capacity(), cap);
        let mut all = Cloud::new(GeometryOptions {
            voxel_size_m: None,
            max_points: 10,
            point_stride: 1,
        });
        all.extend(&[pt(0.01), pt(0.02)]);
        assert_eq!(all.points.len(), 2);
    }
}
