//! Scene geometry (a room with boxes) and exact ray casting; the textures are in
//! `texture.rs`.
//!
//! World frame: metres, z up. The room is an axis-aligned box seen from the inside;
//! boxes are cuboids rotated about the vertical axis (yaw).

use nalgebra::{Point3, Vector3};

use crate::rng::Rng;
use crate::texture::Texture;

/// Number of surface ids used by the room itself (floor, ceiling, four walls).
pub const ROOM_SURFACES: u32 = 6;

/// A cuboid rotated by `yaw` about the world z axis.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneBox {
    centre: Point3<f64>,
    half_extents: Vector3<f64>,
    yaw: f64,
    cos_yaw: f64,
    sin_yaw: f64,
}

impl SceneBox {
    /// Creates a box from its centre, half side lengths (box frame) and yaw (radians).
    pub fn new(centre: Point3<f64>, half_extents: Vector3<f64>, yaw: f64) -> Self {
        Self {
            centre,
            half_extents,
            yaw,
            cos_yaw: yaw.cos(),
            sin_yaw: yaw.sin(),
        }
    }

    /// Creates a box standing on the floor plane `z = floor_z`.
    pub fn on_floor(floor_z: f64, x: f64, y: f64, half_extents: Vector3<f64>, yaw: f64) -> Self {
        Self::new(
            Point3::new(x, y, floor_z + half_extents.z),
            half_extents,
            yaw,
        )
    }

    /// Centre of the box (world frame).
    pub fn centre(&self) -> Point3<f64> {
        self.centre
    }

    /// Half side lengths in the box frame.
    pub fn half_extents(&self) -> Vector3<f64> {
        self.half_extents
    }

    /// Rotation about the world z axis, radians.
    pub fn yaw(&self) -> f64 {
        self.yaw
    }

    /// World vector to box frame (rotation only).
    #[inline]
    fn to_local_vec(&self, v: &Vector3<f64>) -> Vector3<f64> {
        Vector3::new(
            self.cos_yaw * v.x + self.sin_yaw * v.y,
            -self.sin_yaw * v.x + self.cos_yaw * v.y,
            v.z,
        )
    }

    /// Box-frame vector to world frame (rotation only).
    #[inline]
    fn to_world_vec(&self, v: &Vector3<f64>) -> Vector3<f64> {
        Vector3::new(
            self.cos_yaw * v.x - self.sin_yaw * v.y,
            self.sin_yaw * v.x + self.cos_yaw * v.y,
            v.z,
        )
    }

    /// World point to box frame.
    #[inline]
    fn to_local(&self, p: &Point3<f64>) -> Vector3<f64> {
        self.to_local_vec(&(p - self.centre))
    }

    /// Entry intersection of a ray with the box, given the ray origin already in the
    /// box frame: `(t, face)` with `face = 2*axis + side` (`side` 1 for the positive
    /// face). Only hits with `t_min < t < t_max` count.
    #[inline]
    fn intersect_local(
        &self,
        o: &Vector3<f64>,
        dir: &Vector3<f64>,
        t_min: f64,
        t_max: f64,
    ) -> Option<(f64, u32)> {
        let d = self.to_local_vec(dir);
        let h = &self.half_extents;
        let mut t_near = t_min;
        let mut t_far = t_max;
        let mut face = u32::MAX;
        for axis in 0..3 {
            let (oa, da, ha) = (o[axis], d[axis], h[axis]);
            if da == 0.0 {
                if oa.abs() > ha {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / da;
            let (t1, t2) = ((-ha - oa) * inv, (ha - oa) * inv);
            // Entering through the face opposite to the direction of travel.
            let (tn, tf, side) = if da > 0.0 { (t1, t2, 0) } else { (t2, t1, 1) };
            if tn > t_near {
                t_near = tn;
                face = 2 * axis as u32 + side;
            }
            t_far = t_far.min(tf);
            if t_near > t_far {
                return None;
            }
        }
        // face == MAX: the origin is inside the box or the entry is before t_min.
        (face != u32::MAX).then_some((t_near, face))
    }

    /// Entry intersection of a ray with the box (see [`Self::intersect_local`]).
    #[cfg(test)]
    fn intersect(
        &self,
        origin: &Point3<f64>,
        dir: &Vector3<f64>,
        t_min: f64,
    ) -> Option<(f64, u32)> {
        self.intersect_local(&self.to_local(origin), dir, t_min, f64::INFINITY)
    }

    /// Outward unit normal of a face (world frame).
    fn face_normal(&self, face: u32) -> Vector3<f64> {
        let mut n = Vector3::zeros();
        n[(face / 2) as usize] = if face % 2 == 1 { 1.0 } else { -1.0 };
        self.to_world_vec(&n)
    }

    /// Euclidean distance from a point to the box (0 inside).
    pub fn distance(&self, p: &Point3<f64>) -> f64 {
        let o = self.to_local(p);
        let q = o.abs() - self.half_extents;
        q.map(|c| c.max(0.0)).norm()
    }

    /// True if the point is inside or on the box.
    pub fn contains(&self, p: &Point3<f64>) -> bool {
        let o = self.to_local(p);
        (0..3).all(|a| o[a].abs() <= self.half_extents[a])
    }
}

/// Result of a ray cast.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit (`origin + t * dir`).
    pub t: f64,
    /// Hit point, world frame.
    pub point: Point3<f64>,
    /// Unit surface normal on the side the surface is seen from (inward for the room,
    /// outward for boxes), world frame.
    pub normal: Vector3<f64>,
    /// Surface id: 0 floor, 1 ceiling, 2/3 walls at x min/max, 4/5 walls at y min/max,
    /// then `6 + 6 * box + face` with `face = 2 * axis + (1 if positive side)`.
    pub surface: u32,
}

/// Per-origin data precomputed by [`Scene::prepare`] for fast repeated ray casts.
#[derive(Clone, Debug)]
pub struct RayOrigin {
    origin: Point3<f64>,
    /// Per box: origin in the box frame, centre − origin, |centre − origin|² − r².
    boxes: Vec<(Vector3<f64>, Vector3<f64>, f64)>,
}

/// A textured room with boxes.
#[derive(Clone, Debug)]
pub struct Scene {
    room_min: Point3<f64>,
    room_max: Point3<f64>,
    boxes: Vec<SceneBox>,
    textures: Vec<Texture>,
    gains: Vec<f64>,
}

/// Direction towards the (fixed, distant) light used for view-independent shading.
fn light_dir() -> Vector3<f64> {
    Vector3::new(0.3, 0.5, 1.0).normalize()
}

impl Scene {
    /// Builds a scene from the room bounds and boxes; textures are drawn from `seed`.
    ///
    /// Boxes must lie inside the room. Shading is Lambertian-like with a fixed light
    /// direction and is constant per planar face, so brightness constancy holds exactly.
    pub fn new(
        room_min: Point3<f64>,
        room_max: Point3<f64>,
        boxes: Vec<SceneBox>,
        seed: u64,
    ) -> Self {
        let n_surfaces = ROOM_SURFACES as usize + 6 * boxes.len();
        let mut rng = Rng::new(seed);
        let textures = (0..n_surfaces).map(|_| Texture::random(&mut rng)).collect();
        let mut scene = Self {
            room_min,
            room_max,
            boxes,
            textures,
            gains: Vec::new(),
        };
        let l = light_dir();
        scene.gains = (0..n_surfaces as u32)
            .map(|s| 0.75 + 0.25 * scene.surface_normal(s).dot(&l).max(0.0))
            .collect();
        scene
    }

    /// The standard test room (about 6 m x 5 m x 3 m, floor at z = 0, centred on the
    /// z axis) with a cluster of boxes of different sizes near the centre, a stacked box,
    /// a cabinet and a low chest against the walls, and one box floating above the
    /// cluster. The geometry is fixed; `seed` only changes the textures.
    pub fn room(seed: u64) -> Self {
        let room_min = Point3::new(-3.0, -2.5, 0.0);
        let room_max = Point3::new(3.0, 2.5, 3.0);
        let v = Vector3::new;
        let boxes = vec![
            // Central cluster.
            SceneBox::on_floor(0.0, -0.35, 0.05, v(0.30, 0.22, 0.35), 0.3),
            SceneBox::on_floor(0.0, 0.45, -0.15, v(0.25, 0.18, 0.20), -0.5),
            SceneBox::on_floor(0.0, 0.25, 0.35, v(0.14, 0.14, 0.45), 0.1),
            SceneBox::on_floor(0.70, -0.35, 0.05, v(0.12, 0.10, 0.10), 0.9),
            SceneBox::on_floor(0.0, -0.05, -0.45, v(0.20, 0.12, 0.08), 1.2),
            // Against the walls.
            SceneBox::on_floor(0.0, -2.6, 2.1, v(0.35, 0.30, 0.90), 0.0),
            SceneBox::on_floor(0.0, 2.7, -0.8, v(0.25, 0.60, 0.35), 0.0),
            SceneBox::on_floor(0.0, -0.6, -2.3, v(0.70, 0.18, 0.30), 0.0),
            // Floating above the cluster.
            SceneBox::new(Point3::new(0.1, -0.1, 2.1), v(0.30, 0.20, 0.12), 0.4),
        ];
        Self::new(room_min, room_max, boxes, seed)
    }

    /// Stretches the texture of one surface by `scale` (see [`Texture::scaled`]);
    /// e.g. `scale` proportional to the viewing distance keeps its detail in pixels.
    ///
    /// # Panics
    /// If `surface` is not a surface id of this scene or `scale` is not positive.
    pub fn scale_texture(&mut self, surface: u32, scale: f64) {
        assert!(scale > 0.0 && scale.is_finite(), "texture scale {scale}");
        let t = &mut self.textures[surface as usize];
        *t = t.scaled(scale);
    }

    /// Multiplies the texture contrast of every surface by `factor` (0 < factor ≤ 1:
    /// weaker texture, down to blank walls; the per-face shading stays, so the edges
    /// between faces still show).
    ///
    /// # Panics
    /// If `factor` is not in (0, 1].
    pub fn scale_contrast(&mut self, factor: f64) {
        assert!(factor > 0.0 && factor <= 1.0, "texture contrast {factor}");
        for t in &mut self.textures {
            *t = t.with_contrast(factor);
        }
    }

    /// Lower corner of the room.
    pub fn room_min(&self) -> Point3<f64> {
        self.room_min
    }

    /// Upper corner of the room.
    pub fn room_max(&self) -> Point3<f64> {
        self.room_max
    }

    /// The boxes in the room.
    pub fn boxes(&self) -> &[SceneBox] {
        &self.boxes
    }

    /// Total number of surface ids.
    pub fn surface_count(&self) -> u32 {
        self.textures.len() as u32
    }

    /// Unit normal of a surface on its visible side (room: inward, boxes: outward).
    pub fn surface_normal(&self, surface: u32) -> Vector3<f64> {
        if surface < ROOM_SURFACES {
            let mut n = Vector3::zeros();
            n[[2, 2, 0, 0, 1, 1][surface as usize]] =
                if surface.is_multiple_of(2) { 1.0 } else { -1.0 };
            n
        } else {
            let s = surface - ROOM_SURFACES;
            self.boxes[(s / 6) as usize].face_normal(s % 6)
        }
    }

    /// Signed distance of `p` from the (infinite) plane of a surface, positive on the
    /// visible side.
    pub fn plane_distance(&self, surface: u32, p: &Point3<f64>) -> f64 {
        let n = self.surface_normal(surface);
        if surface < ROOM_SURFACES {
            let axis = [2, 2, 0, 0, 1, 1][surface as usize];
            if surface.is_multiple_of(2) {
                p[axis] - self.room_min[axis]
            } else {
                self.room_max[axis] - p[axis]
            }
        } else {
            let s = surface - ROOM_SURFACES;
            let b = &self.boxes[(s / 6) as usize];
            let axis = ((s % 6) / 2) as usize;
            (p - b.centre).dot(&n) - b.half_extents[axis]
        }
    }

    /// True if `p` is strictly inside the room and outside every box.
    pub fn is_free(&self, p: &Point3<f64>) -> bool {
        (0..3).all(|a| p[a] > self.room_min[a] && p[a] < self.room_max[a])
            && !self.boxes.iter().any(|b| b.contains(p))
    }

    /// Distance from `p` to the nearest surface (room walls, floor, ceiling or box);
    /// 0 if `p` is not in free space.
    pub fn clearance(&self, p: &Point3<f64>) -> f64 {
        if !self.is_free(p) {
            return 0.0;
        }
        let mut d = f64::INFINITY;
        for a in 0..3 {
            d = d.min(p[a] - self.room_min[a]).min(self.room_max[a] - p[a]);
        }
        self.boxes.iter().fold(d, |d, b| d.min(b.distance(p)))
    }

    /// Precomputes per-origin data for repeated casts from the same point.
    pub fn prepare(&self, origin: &Point3<f64>) -> RayOrigin {
        RayOrigin {
            origin: *origin,
            boxes: self
                .boxes
                .iter()
                .map(|b| {
                    let oc = b.centre - origin;
                    let r = b.half_extents.norm();
                    (b.to_local(origin), oc, oc.norm_squared() - r * r)
                })
                .collect(),
        }
    }

    /// Casts a ray (origin inside the room, any non-zero direction) and returns the
    /// nearest hit, or `None` if the origin is outside the room.
    pub fn cast(&self, origin: &Point3<f64>, dir: &Vector3<f64>) -> Option<Hit> {
        self.cast_from(&self.prepare(origin), dir)
    }

    /// [`Self::cast`] from a prepared origin.
    #[inline]
    pub fn cast_from(&self, prepared: &RayOrigin, dir: &Vector3<f64>) -> Option<Hit> {
        let origin = &prepared.origin;
        // Exit point of the room (the room is seen from inside).
        let mut t_best = f64::INFINITY;
        let mut surface = u32::MAX;
        for (axis, ids) in [(0usize, [2u32, 3]), (1, [4, 5]), (2, [0, 1])] {
            let d = dir[axis];
            if d == 0.0 {
                continue;
            }
            let (bound, id) = if d > 0.0 {
                (self.room_max[axis], ids[1])
            } else {
                (self.room_min[axis], ids[0])
            };
            let t = (bound - origin[axis]) / d;
            if t < t_best {
                t_best = t;
                surface = id;
            }
        }
        if !(t_best > 0.0 && t_best.is_finite()) {
            return None;
        }
        let dd = dir.norm_squared();
        for (i, (b, (local, oc, c2))) in self.boxes.iter().zip(&prepared.boxes).enumerate() {
            // Bounding-sphere rejection: the ray line misses the sphere, or the sphere is
            // behind an origin outside it.
            let bdot = oc.dot(dir);
            if bdot * bdot < dd * c2 || (*c2 > 0.0 && bdot < 0.0) {
                continue;
            }
            if let Some((t, face)) = b.intersect_local(local, dir, 0.0, t_best) {
                t_best = t;
                surface = ROOM_SURFACES + 6 * i as u32 + face;
            }
        }
        Some(Hit {
            t: t_best,
            point: origin + dir * t_best,
            normal: self.surface_normal(surface),
            surface,
        })
    }

    /// 2-D texture coordinates (metres) of a point on a surface.
    fn surface_uv(&self, surface: u32, p: &Point3<f64>) -> (f64, f64) {
        if surface < ROOM_SURFACES {
            match surface {
                0 | 1 => (p.x, p.y),
                2 | 3 => (p.y, p.z),
                _ => (p.x, p.z),
            }
        } else {
            let s = surface - ROOM_SURFACES;
            let b = &self.boxes[(s / 6) as usize];
            let l = b.to_local(p);
            match (s % 6) / 2 {
                0 => (l.y, l.z),
                1 => (l.x, l.z),
                _ => (l.x, l.y),
            }
        }
    }

    /// View-independent intensity (0–255, not rounded) of a surface point: procedural
    /// texture times a constant per-face Lambertian gain.
    #[inline]
    pub fn radiance(&self, surface: u32, p: &Point3<f64>) -> f64 {
        let (u, v) = self.surface_uv(surface, p);
        self.textures[surface as usize].eval(u, v) * self.gains[surface as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_intersection_and_normals() {
        let b = SceneBox::new(
            Point3::new(1.0, 0.0, 0.5),
            Vector3::new(0.5, 0.25, 0.5),
            0.0,
        );
        let (t, face) = b
            .intersect(&Point3::new(-1.0, 0.0, 0.5), &Vector3::x(), 0.0)
            .unwrap();
        assert!((t - 1.5).abs() < 1e-12);
        assert_eq!(face, 0);
        assert_eq!(b.face_normal(face), -Vector3::x());
        assert!(
            b.intersect(&Point3::new(-1.0, 1.0, 0.5), &Vector3::x(), 0.0)
                .is_none()
        );
        // Rotated by 90°: the extent along world x is now 0.25.
        let r = SceneBox::new(b.centre(), b.half_extents(), std::f64::consts::FRAC_PI_2);
        let (t, _) = r
            .intersect(&Point3::new(-1.0, 0.0, 0.5), &Vector3::x(), 0.0)
            .unwrap();
        assert!((t - 1.75).abs() < 1e-12);
        assert!((r.distance(&Point3::new(1.0, 0.0, 2.0)) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn cast_hits_walls_and_boxes_on_their_planes() {
        let scene = Scene::room(3);
        let o = Point3::new(1.5, 1.2, 1.4);
        let mut rng = Rng::new(9);
        let mut seen = std::collections::HashSet::new();
        for _ in 0..5000 {
            let d = Vector3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            let h = scene.cast(&o, &d).unwrap();
            seen.insert(h.surface);
            assert!(scene.plane_distance(h.surface, &h.point).abs() < 1e-9);
            // The surface faces the camera.
            assert!(h.normal.dot(&d) < 0.0);
        }
        assert!(seen.len() > 12, "only {} surfaces seen", seen.len());
        assert!(
            scene
                .cast(&Point3::new(10.0, 0.0, 1.0), &Vector3::x())
                .is_none()
        );
    }
}
