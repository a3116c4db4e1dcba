//! Triangle meshes read from Wavefront OBJ files (the `tobj` crate, faces triangulated) under a
//! bounding volume hierarchy (the `bvh` crate, SAH): the nearest hit of a ray, and whether a
//! point lies inside a closed mesh. Surfaces ([`super::surface`]) and
//! fog bounded by a mesh ([`super::medium::Fog`]) share it.
//!
//! Ray–triangle intersection by Möller & Trumbore (1997): with edges e₁ = b − a, e₂ = c − a,
//! p = w × e₂, det = e₁ · p, s = o − a, u = (s · p)/det, q = s × e₁, v = (w · q)/det, the hit
//! is at t = (e₂ · q)/det when u ≥ 0, v ≥ 0, u + v ≤ 1.
//!
//! Inside a closed mesh: a ray from the point crosses the surface an odd number of times. The
//! ray's direction is fixed and irrational to the axes, so that it meets edges and vertices of
//! a mesh built on a grid with probability 0.

use super::geometry::{box_clip, cross, dot, normalize, outside_box, self_hit_distance, Vec3};
use anyhow::{ensure, Context, Result};
use bvh::aabb::{Aabb, Bounded};
use bvh::bounding_hierarchy::BHShape;
use bvh::bvh::Bvh;
use nalgebra::{Point3, Vector3};
use std::path::Path;

/// One triangle and its place in the hierarchy.
#[derive(Clone, Copy, Debug)]
struct Triangle {
    a: Vec3,
    b: Vec3,
    c: Vec3,
    node: usize,
}

impl Bounded<f64, 3> for Triangle {
    fn aabb(&self) -> Aabb<f64, 3> {
        let lo: Vec3 = std::array::from_fn(|k| self.a[k].min(self.b[k]).min(self.c[k]));
        let hi: Vec3 = std::array::from_fn(|k| self.a[k].max(self.b[k]).max(self.c[k]));
        Aabb::with_bounds(Point3::from(lo), Point3::from(hi))
    }
}

impl BHShape<f64, 3> for Triangle {
    fn set_bh_node_index(&mut self, index: usize) {
        self.node = index;
    }

    fn bh_node_index(&self) -> usize {
        self.node
    }
}

impl Triangle {
    /// The distance t > `eps` at which o + t w meets the triangle, if it does.
    fn hit(&self, o: Vec3, w: Vec3, eps: f64) -> Option<f64> {
        let sub = |x: Vec3, y: Vec3| -> Vec3 { std::array::from_fn(|k| x[k] - y[k]) };
        let (e1, e2) = (sub(self.b, self.a), sub(self.c, self.a));
        let p = cross(w, e2);
        let det = dot(e1, p);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let s = sub(o, self.a);
        let u = dot(s, p) / det;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = cross(s, e1);
        let v = dot(w, q) / det;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = dot(e2, q) / det;
        (t > eps).then_some(t)
    }

    /// The unit geometric normal (b − a) × (c − a) / |…| (counter-clockwise faces outward).
    fn normal(&self) -> Vec3 {
        let sub = |x: Vec3, y: Vec3| -> Vec3 { std::array::from_fn(|k| x[k] - y[k]) };
        normalize(cross(sub(self.b, self.a), sub(self.c, self.a)))
    }
}

/// A triangle mesh under a BVH.
pub struct TriangleMesh {
    triangles: Vec<Triangle>,
    bvh: Bvh<f64, 3>,
    lo: Vec3,
    hi: Vec3,
    open_edges: usize,
}

/// The direction of the inside test's rays (unit, irrational to the axes).
const PARITY_RAY: Vec3 = [0.539_965_987_1, 0.606_339_816_4, 0.583_835_710_2];

impl TriangleMesh {
    /// The triangles of every object of the OBJ file at `path` (faces triangulated; units m).
    pub fn load(path: &Path) -> Result<Self> {
        let what = || format!("mesh '{}'", path.display());
        let options = tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        };
        let (models, _) = tobj::load_obj(path, &options).with_context(what)?;
        let mut triangles = Vec::new();
        // Each edge of a closed surface belongs to two faces (by vertex index, per object).
        let mut edges = std::collections::HashMap::new();
        for (o, m) in models.iter().enumerate() {
            let p = &m.mesh.positions;
            let vertex = |i: u32| -> Vec3 { std::array::from_fn(|k| p[3 * i as usize + k]) };
            for f in m.mesh.indices.chunks_exact(3) {
                for (a, b) in [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])] {
                    *edges.entry((o, a.min(b), a.max(b))).or_insert(0usize) += 1;
                }
                triangles.push(Triangle {
                    a: vertex(f[0]),
                    b: vertex(f[1]),
                    c: vertex(f[2]),
                    node: 0,
                });
            }
        }
        ensure!(!triangles.is_empty(), "{}: no faces", what());
        ensure!(
            triangles
                .iter()
                .all(|t| [t.a, t.b, t.c].iter().flatten().all(|x| x.is_finite())),
            "{}: vertices must be finite",
            what()
        );
        let mut mesh = Self::new(triangles);
        mesh.open_edges = edges.values().filter(|&&n| n != 2).count();
        Ok(mesh)
    }

    /// Edges that do not belong to exactly two faces (by vertex index; 0 for a closed mesh
    /// read from a file, unknown — 0 — for one built from bare triangles).
    pub fn open_edges(&self) -> usize {
        self.open_edges
    }

    /// The mesh of the triangles [a, b, c] (m).
    pub fn from_triangles(triangles: &[[Vec3; 3]]) -> Self {
        Self::new(
            triangles
                .iter()
                .map(|&[a, b, c]| Triangle { a, b, c, node: 0 })
                .collect(),
        )
    }

    fn new(mut triangles: Vec<Triangle>) -> Self {
        let bvh = Bvh::build(&mut triangles);
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for t in &triangles {
            for v in [t.a, t.b, t.c] {
                for k in 0..3 {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
        }
        Self {
            triangles,
            bvh,
            lo,
            hi,
            open_edges: 0,
        }
    }

    /// The mesh's bounding box (lowest and highest corners, m).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.lo, self.hi)
    }

    /// Calls `f` on the triangles whose boxes the ray o + t w (t ≥ 0) passes through (no
    /// allocation: the hierarchy is walked by an iterator).
    fn for_candidates(&self, o: Vec3, w: Vec3, mut f: impl FnMut(&Triangle)) {
        // Most rays of a scene miss a given mesh: its box first, without the hierarchy.
        let pad = |x: f64, s: f64| x + s * (1e-9 + 1e-7 * x.abs());
        let lo = self.lo.map(|x| pad(x, -1.0));
        let hi = self.hi.map(|x| pad(x, 1.0));
        // (Padded: a flat mesh has a box of zero thickness.)
        if box_clip(o, w, lo, hi).is_none() {
            return;
        }
        let ray = bvh::ray::Ray::new(Point3::from(o), Vector3::from(w));
        for tri in self.bvh.traverse_iterator(&ray, &self.triangles) {
            f(tri);
        }
    }

    /// The nearest hit of o + t w with t in (ε, t_max): its distance and unit geometric
    /// normal.
    pub fn intersect(&self, o: Vec3, w: Vec3, t_max: f64) -> Option<(f64, Vec3)> {
        let eps = self_hit_distance(o);
        let mut best: Option<(f64, Vec3)> = None;
        self.for_candidates(o, w, |tri| {
            let reach = best.map_or(t_max, |(t, _)| t);
            if let Some(t) = tri.hit(o, w, eps).filter(|&t| t < reach) {
                best = Some((t, tri.normal()));
            }
        });
        best
    }

    /// Whether `p` lies inside the (closed) mesh: an odd number of crossings along a fixed ray.
    pub fn contains(&self, p: Vec3) -> bool {
        if outside_box(p, self.lo, self.hi) {
            return false;
        }
        let w = normalize(PARITY_RAY);
        let mut crossings = 0usize;
        self.for_candidates(p, w, |tri| {
            crossings += usize::from(tri.hit(p, w, 0.0).is_some());
        });
        crossings % 2 == 1
    }

    /// Whether any triangle's bounding box overlaps the box [lo, hi]: a conservative test of
    /// whether the surface passes through it.
    pub fn touches_box(&self, lo: Vec3, hi: Vec3) -> bool {
        let query = Aabb::with_bounds(Point3::from(lo), Point3::from(hi));
        self.bvh
            .traverse_iterator(&query, &self.triangles)
            .any(|t| t.aabb().intersects_aabb(&query))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit cube [0, 1]³ as 12 triangles, faces counter-clockwise from outside.
    fn cube() -> TriangleMesh {
        let v = |i: usize| -> Vec3 { [(i & 1) as f64, ((i >> 1) & 1) as f64, (i >> 2) as f64] };
        let quads = [
            [0, 2, 3, 1], // z = 0, facing −z
            [4, 5, 7, 6], // z = 1
            [0, 1, 5, 4], // y = 0
            [2, 6, 7, 3], // y = 1
            [0, 4, 6, 2], // x = 0
            [1, 3, 7, 5], // x = 1
        ];
        let mut tris = Vec::new();
        for q in quads {
            tris.push([v(q[0]), v(q[1]), v(q[2])]);
            tris.push([v(q[0]), v(q[2]), v(q[3])]);
        }
        TriangleMesh::from_triangles(&tris)
    }

    #[test]
    fn a_cube_is_hit_on_the_right_face_and_holds_its_inside() {
        let m = cube();
        let (t, n) = m
            .intersect([0.3, 0.4, 5.0], [0.0, 0.0, -1.0], f64::INFINITY)
            .expect("hit");
        assert!(
            (t - 4.0).abs() < 1e-12 && (n[2] - 1.0).abs() < 1e-12,
            "{t} {n:?}"
        );
        assert!(m
            .intersect([0.3, 0.4, 5.0], [0.0, 0.0, -1.0], 3.9)
            .is_none());
        assert!(m.contains([0.5, 0.5, 0.5]) && m.contains([0.01, 0.99, 0.2]));
        assert!(!m.contains([1.5, 0.5, 0.5]) && !m.contains([0.5, -0.01, 0.5]));
        // Outward normals: the face at x = 1 faces +x.
        let (_, n) = m
            .intersect([3.0, 0.5, 0.5], [-1.0, 0.0, 0.0], f64::INFINITY)
            .expect("hit");
        assert!((n[0] - 1.0).abs() < 1e-12, "{n:?}");
        assert!(m.touches_box([0.9, 0.2, 0.2], [1.1, 0.3, 0.3]));
    }

    #[test]
    fn a_flat_mesh_is_hit_though_its_box_has_no_thickness() {
        let (a, b, c, d) = (
            [0.0, 0.0, 1.0],
            [2.0, 0.0, 1.0],
            [2.0, 2.0, 1.0],
            [0.0, 2.0, 1.0],
        );
        let m = TriangleMesh::from_triangles(&[[a, b, c], [a, c, d]]);
        let (t, n) = m
            .intersect([0.5, 1.5, 3.0], [0.0, 0.0, -1.0], f64::INFINITY)
            .expect("hit");
        assert!(
            (t - 2.0).abs() < 1e-12 && (n[2] - 1.0).abs() < 1e-12,
            "{t} {n:?}"
        );
        let w = normalize([0.3, 0.2, 1.0]);
        assert!(m.intersect([0.5, 0.5, 0.0], w, f64::INFINITY).is_some());
    }
}
