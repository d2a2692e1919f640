//! Vectors and axis-aligned boxes.
//!
//! `Vec3` is glam's `DVec3` (re-exported by parry3d-f64); everything in the core is f64.

pub use parry3d_f64::math::Vector as Vec3;

/// An axis-aligned box `[min, max]` (closed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Aabb {
    /// A box from its corners.
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Aabb { min, max }
    }

    /// The empty box (min = +inf, max = -inf), the identity of [`Aabb::union`].
    pub fn empty() -> Self {
        Aabb { min: Vec3::splat(f64::INFINITY), max: Vec3::splat(f64::NEG_INFINITY) }
    }

    /// The smallest box containing `points`.
    pub fn from_points(points: &[Vec3]) -> Self {
        let mut b = Aabb::empty();
        for p in points {
            b.min = b.min.min(*p);
            b.max = b.max.max(*p);
        }
        b
    }

    /// The smallest box containing both.
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    /// Closed-box overlap test.
    #[inline]
    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.min.x <= o.max.x && o.min.x <= self.max.x && self.min.y <= o.max.y && o.min.y <= self.max.y && self.min.z <= o.max.z && o.min.z <= self.max.z
    }

    /// Distance from `p` to the closed box (0 inside).
    #[inline]
    pub fn distance_to_point(&self, p: Vec3) -> f64 {
        self.distance_squared_to_point(p).sqrt()
    }

    /// The squared distance from `p` to the box (0 inside).
    #[inline]
    pub fn distance_squared_to_point(&self, p: Vec3) -> f64 {
        (self.min - p).max(p - self.max).max(Vec3::ZERO).length_squared()
    }

    /// Whether `p` lies in the closed box.
    #[inline]
    pub fn contains_point(&self, p: Vec3) -> bool {
        p.x >= self.min.x && p.x <= self.max.x && p.y >= self.min.y && p.y <= self.max.y && p.z >= self.min.z && p.z <= self.max.z
    }

    /// Centre.
    #[inline]
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Half extents.
    #[inline]
    pub fn half(&self) -> Vec3 {
        (self.max - self.min) * 0.5
    }

    /// Edge lengths.
    #[inline]
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// Length of the diagonal.
    pub fn diagonal(&self) -> f64 {
        self.extent().length()
    }

    /// The box grown by `r` on every side.
    pub fn inflated(&self, r: f64) -> Aabb {
        Aabb { min: self.min - Vec3::splat(r), max: self.max + Vec3::splat(r) }
    }

    /// Whether the segment `a → b` meets the closed box (slab test).
    pub fn overlaps_segment(&self, a: Vec3, b: Vec3) -> bool {
        let d = b - a;
        let mut t0 = 0.0f64;
        let mut t1 = 1.0f64;
        for k in 0..3 {
            let (lo, hi, o, dk) = (self.min[k], self.max[k], a[k], d[k]);
            if dk.abs() < 1e-300 {
                if o < lo || o > hi {
                    return false;
                }
            } else {
                let mut ta = (lo - o) / dk;
                let mut tb = (hi - o) / dk;
                if ta > tb {
                    std::mem::swap(&mut ta, &mut tb);
                }
                t0 = t0.max(ta);
                t1 = t1.min(tb);
                if t0 > t1 {
                    return false;
                }
            }
        }
        true
    }
}
