//! The BVH every ray query traverses: obvhs's binary BVH collapsed into eight-wide nodes whose
//! child boxes are tested eight at a time, with leaves of up to four triangles tested four at a
//! time, as Embree's BVH8 + `Triangle4` (Wald et al. 2014).
//!
//! * **Nodes** ([`Node8`]): eight exact child boxes ([`WideBvh::from_bvh2`]) in f32
//!   structure-of-arrays form (lower and upper bound per axis, eight lanes each), 256 bytes; an
//!   empty slot is the inverted box [+∞, −∞], which no ray meets. One slab test of eight boxes:
//!   `t = (bound − o)·(1/d)` per axis, the near and far bound chosen once per ray from the signs
//!   of `1/d`.
//! * **Leaves** ([`Tri4`]): four triangles as `v0`, `e1 = v0 − v1`, `e2 = v2 − v0` per lane, tested
//!   by obvhs's Möller–Trumbore variant with the same operations in the same order, so that each
//!   distance is bit for bit the one `obvhs::triangle::Triangle::intersect` returns (test
//!   `wide_traversal_matches_brute_force`).
//! * **Order**: a closest-hit query tests a node's leaves when it visits the node (a hit shortens
//!   the ray), visits the inner children it meets nearest first (a stack sorted by entry distance)
//!   and skips any whose entry lies beyond the closest hit so far. An occlusion query stops at
//!   the first accepted hit and visits children in the slot order of the ray's octant. Both ask
//!   for the memory of the children they will visit (prefetch) before testing a node's leaves:
//!   on 10⁵–10⁶ triangles the loads of nodes and packs, not the arithmetic, are most of the time
//!   (+20–30 % rays per second on incoherent rays).
//!
//! It replaced obvhs's CWBVH (Ylitie et al. 2017) traversal, a port of a GPU design: child boxes
//! quantised to bytes and converted at every visit, octant order for closest hits, leaves of at
//! most three triangles through a per-triangle closure. On the `rays` bench (docs/results/
//! benchmarks-rays.md, best of three runs) it raised our throughput from 0.38–0.82× Embree's to 0.67–1.25×.
//!
//! The caller decides what a geometric hit means (`accept`): a face to skip, a cut-out's hole, a
//! back face's tie margin (see [`super::SceneBvh`]). It is called only for lanes whose triangle the
//! ray meets within its current range, not for every triangle tested.
//!
//! It is safe code over `wide`'s vectors (SSE2 on every x86-64; other targets get the same
//! results from its scalar fallback), but for the node test on CPUs with AVX: `wide` builds its
//! eight lanes from two SSE halves unless the whole program is compiled for AVX, so the
//! traversals have a second copy compiled for AVX ([`Slab::test_avx`]: one 256-bit register per
//! bound), chosen when the BVH is built by asking the CPU — the project's only `unsafe`: the two
//! calls into that copy. The same bits either way (the test below runs both); on the `rays` bench
//! the 10⁶-triangle incoherent rays went from 0.66–0.71× Embree's rays per second to 0.72–0.82×
//! (three runs), as fast as the whole program compiled with `-C target-cpu=native` (0.73–0.77 in
//! one run). Choosing the stack through a closure (`with_stack`, one function for both queries)
//! lost 15–20 % of that: the traversal then stopped being inlined into the AVX copy.

use crate::sample::prefetch;
use glam::Vec3A;
use obvhs::{bvh2::Bvh2, triangle::Triangle};
use wide::{CmpGe, CmpLe, CmpNe, f32x4, f32x8};

/// Set on a [`Node8`] child that is a leaf; the rest of its bits are `pack << 4 | lane << 2 |
/// (count − 1)`: its 1–4 triangles are lanes `lane .. lane + count` of [`WideBvh::packs`]`[pack]`.
const LEAF: u32 = 1 << 31;

/// Entries of a traversal stack on the thread's stack: a node pushes at most seven entries more than
/// it pops, so a tree `D` levels deep needs at most `7·D + 8`. A query takes a stack of `STACK / 4`
/// entries when that suffices (`D` ≤ 8), else of `STACK` (`D` ≤ 35), else one on the heap
/// (degenerate geometry).
const STACK: usize = 256;

/// Eight child boxes in structure-of-arrays form and what each child is: 224 bytes in four
/// cache lines of their own.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Node8 {
    /// Lower x, upper x, lower y, upper y, lower z, upper z of the eight children.
    bounds: [f32x8; 6],
    /// Per child: a node index, or a leaf ([`LEAF`]).
    child: [u32; 8],
    /// Bit `i` set when child `i` is a leaf.
    leaves: u32,
}

/// Four triangles of one node's leaves, lane by lane (a node's leaves share packs: one pack per
/// leaf of 1.9 triangles on average filled half the lanes, and packs are most of the memory).
#[derive(Clone, Copy, Debug)]
struct Tri4 {
    /// `v0`, `e1`, `e2` of obvhs's test: x, y, z of each (its `n = e1 × e2` is computed per test,
    /// with the same operations).
    v0: [f32x4; 3],
    e1: [f32x4; 3],
    e2: [f32x4; 3],
    /// The face (the scene's triangle index) of each lane.
    prim: [u32; 4],
}

/// The decoded wide BVH (module docs).
#[derive(Clone, Debug)]
pub(crate) struct WideBvh {
    nodes: Vec<Node8>,
    packs: Vec<Tri4>,
    /// The entries a traversal stack needs (module docs of [`STACK`]).
    stack_len: usize,
    /// Whether the CPU has AVX: the traversals then run their AVX versions (`closest_avx`,
    /// `any_avx`). Tests clear it to check the SSE versions on the same machine.
    avx: bool,
}

/// A ray in the BVH's frame: `origin + t·direction` for `t` in `[tmin, tmax]` (the slab tests
/// take its inverse direction once, [`Slab::new`]; obvhs's `Ray` computed one more per ray).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ray {
    pub(crate) origin: Vec3A,
    pub(crate) direction: Vec3A,
    pub(crate) tmin: f32,
    pub(crate) tmax: f32,
}

/// A ray prepared for the slab tests: `o`, `1/d` and which bound is near on each axis.
struct Slab {
    o: [f32x8; 3],
    inv: [f32x8; 3],
    /// Index into [`Node8::bounds`] of the near bound per axis (the far one is `near ^ 1`).
    near: [usize; 3],
}

impl Slab {
    fn new(ray: &Ray) -> Self {
        // |d| ≥ 10⁻³⁰ per axis, so 1/d is finite and (b − o)/d is never 0·∞ (obvhs's
        // `Ray::inv_direction` clamps |1/d| to 2²³ instead, which shortens the slab of a
        // direction near an axis)
        let inv = |c: f32| {
            1.0 / if c.abs() < 1e-30 {
                1e-30f32.copysign(c)
            } else {
                c
            }
        };
        let inv = Vec3A::new(
            inv(ray.direction.x),
            inv(ray.direction.y),
            inv(ray.direction.z),
        );
        let o = ray.origin;
        let near = |axis: usize, i: f32| 2 * axis + usize::from(i < 0.0);
        Slab {
            o: [f32x8::splat(o.x), f32x8::splat(o.y), f32x8::splat(o.z)],
            inv: [
                f32x8::splat(inv.x),
                f32x8::splat(inv.y),
                f32x8::splat(inv.z),
            ],
            near: [near(0, inv.x), near(1, inv.y), near(2, inv.z)],
        }
    }

    /// The eight children's entry distances and the mask of those the ray meets within
    /// `[tmin, tmax]`.
    #[inline(always)]
    fn test(&self, node: &Node8, tmin: f32, tmax: f32) -> ([f32; 8], u32) {
        let b = &node.bounds;
        let t = |axis: usize, which: usize| (b[which] - self.o[axis]) * self.inv[axis];
        let [nx, ny, nz] = self.near;
        let near = (t(0, nx).fast_max(t(1, ny))).fast_max(t(2, nz).fast_max(f32x8::splat(tmin)));
        let far = (t(0, nx ^ 1).fast_min(t(1, ny ^ 1)))
            .fast_min(t(2, nz ^ 1).fast_min(f32x8::splat(tmax)));
        (near.to_array(), near.cmp_le(far).move_mask() as u32)
    }

    /// [`Slab::test`] in one AVX register per bound (the same operations in the same order,
    /// hence the same bits): `wide` builds its eight lanes from two SSE halves unless the whole
    /// program is compiled for AVX, and on 10⁶ triangles the halves cost 10–15 % of the
    /// incoherent rays per second.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn test_avx(&self, node: &Node8, tmin: f32, tmax: f32) -> ([f32; 8], u32) {
        use std::arch::x86_64::{
            __m256, _CMP_LE_OS, _mm256_cmp_ps, _mm256_max_ps, _mm256_min_ps, _mm256_movemask_ps,
            _mm256_mul_ps, _mm256_set1_ps, _mm256_sub_ps,
        };
        let m = |v: f32x8| -> __m256 { bytemuck::cast(v) };
        let b = &node.bounds;
        let t = |axis: usize, which: usize| {
            _mm256_mul_ps(
                _mm256_sub_ps(m(b[which]), m(self.o[axis])),
                m(self.inv[axis]),
            )
        };
        let [nx, ny, nz] = self.near;
        let near = _mm256_max_ps(
            _mm256_max_ps(t(0, nx), t(1, ny)),
            _mm256_max_ps(t(2, nz), _mm256_set1_ps(tmin)),
        );
        let far = _mm256_min_ps(
            _mm256_min_ps(t(0, nx ^ 1), t(1, ny ^ 1)),
            _mm256_min_ps(t(2, nz ^ 1), _mm256_set1_ps(tmax)),
        );
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OS>(near, far));
        (bytemuck::cast(near), mask as u32)
    }
}

impl Tri4 {
    /// obvhs's `Triangle::intersect` on the lanes of `lanes`: per lane the distance when the ray
    /// meets the triangle within `[tmin, tmax]` (same operations in the same order, hence the
    /// same bits), and the mask of those lanes.
    #[inline(always)]
    fn intersect(
        &self,
        o: &[f32x4; 3],
        d: &[f32x4; 3],
        tmin: f32,
        tmax: f32,
        lanes: u32,
    ) -> ([f32; 4], u32) {
        let dot = |a: &[f32x4; 3], b: &[f32x4; 3]| (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
        let (e1, e2) = (&self.e1, &self.e2);
        // n = e1 × e2
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let c = [self.v0[0] - o[0], self.v0[1] - o[1], self.v0[2] - o[2]];
        // r = d × c
        let r = [
            d[1] * c[2] - d[2] * c[1],
            d[2] * c[0] - d[0] * c[2],
            d[0] * c[1] - d[1] * c[0],
        ];
        let inv_det = f32x4::ONE / dot(&n, d);
        let u = dot(&r, &self.e2) * inv_det;
        let v = dot(&r, &self.e1) * inv_det;
        let w = (f32x4::ONE - u) - v;
        let t = dot(&n, &c) * inv_det;
        // valid: no sign bit in u, v, w (−0 included, as obvhs), inv_det ≠ 0, t in range
        let negative = (u | v | w).move_mask() as u32;
        let ok = inv_det.cmp_ne(f32x4::ZERO)
            & t.cmp_ge(f32x4::splat(tmin))
            & t.cmp_le(f32x4::splat(tmax));
        (t.to_array(), ok.move_mask() as u32 & !negative & lanes)
    }
}

/// A [`Tri4`] being filled lane by lane.
#[derive(Clone, Copy, Debug, Default)]
struct PackBuilder {
    /// `v0`, `e1`, `e2` per axis, per lane.
    a: [[f32; 4]; 9],
    prim: [u32; 4],
    /// Lanes filled.
    used: usize,
}

impl PackBuilder {
    /// Fills the next lane with triangle `t`, face `prim`.
    fn push(&mut self, t: &Triangle, prim: u32) {
        let lane = self.used;
        for (j, v) in [t.v0, t.v0 - t.v1, t.v2 - t.v0].iter().enumerate() {
            for axis in 0..3 {
                self.a[3 * j + axis][lane] = v[axis];
            }
        }
        self.prim[lane] = prim;
        self.used += 1;
    }

    fn finish(&self) -> Tri4 {
        let v = |j: usize| [j, j + 1, j + 2].map(|k| f32x4::new(self.a[k]));
        Tri4 {
            v0: v(0),
            e1: v(3),
            e2: v(6),
            prim: self.prim,
        }
    }
}

/// Whether this CPU runs AVX instructions (asked once per BVH).
fn has_avx() -> bool {
    #[cfg(target_arch = "x86_64")]
    return std::arch::is_x86_feature_detected!("avx");
    #[cfg(not(target_arch = "x86_64"))]
    return false;
}

/// The ray's origin and direction splatted over four lanes.
fn splat4(v: Vec3A) -> [f32x4; 3] {
    [f32x4::splat(v.x), f32x4::splat(v.y), f32x4::splat(v.z)]
}

impl WideBvh {
    /// Collapses obvhs's binary BVH `bvh2` over `tris` (the scene's triangles in its order) into
    /// eight-wide nodes.
    ///
    /// Top down, a node takes its binary node's two children and opens the largest (by surface
    /// area) inner one among them until it has eight or only leaves (as Embree's BVH8 builder
    /// does). The children's boxes are the binary nodes' exact ones (with spatial splits a leaf's
    /// box bounds only its part of a triangle), padded by 2⁻¹⁹ of the largest coordinate: the f32
    /// slab test's rounding, at most a few 2⁻²⁴ of the coordinates' size in units of t, stays
    /// below the pad, so no box a ray crosses, flat ones (a wall's triangles) included, is
    /// missed. The children are laid out in slots as CWBVH lays them out (Ylitie et al. 2017,
    /// §3.2): slot `s` takes the child farthest back along the octant direction `s ^ 7`, so that
    /// visiting slots `o ^ 7, …` for a ray in octant `o` goes roughly front to back. A node's
    /// leaves (≤ 4 triangles each) share four-lane packs, first fit by decreasing size, a leaf
    /// never split between two packs.
    pub(crate) fn from_bvh2(bvh2: &Bvh2, tris: &[Triangle]) -> Self {
        let mut wide = WideBvh {
            nodes: Vec::new(),
            packs: Vec::new(),
            stack_len: 0,
            avx: has_avx(),
        };
        if bvh2.nodes.is_empty() {
            return wide;
        }
        let largest = (tris.iter())
            .flat_map(|t| [t.v0, t.v1, t.v2])
            .fold(0f32, |m, v| m.max(v.abs().max_element()));
        let pad = largest * 2f32.powi(-19);
        let empty = Node8 {
            bounds: [f32x8::splat(f32::INFINITY), f32x8::splat(f32::NEG_INFINITY)].repeat(3)[..6]
                .try_into()
                .expect("six bounds"),
            child: [0; 8],
            leaves: 0,
        };
        wide.nodes.push(empty);
        let mut packs: Vec<PackBuilder> = Vec::new();
        // (binary node, wide node, depth)
        let mut todo = vec![(0usize, 0usize, 0usize)];
        let mut deepest = 0;
        while let Some((b, w, depth)) = todo.pop() {
            deepest = deepest.max(depth);
            let node = &bvh2.nodes[b];
            // the children: open the largest inner one until there are eight
            let mut kids = if node.is_leaf() {
                vec![b]
            } else {
                vec![node.first_index as usize, node.first_index as usize + 1]
            };
            while kids.len() < 8 {
                let open = (0..kids.len())
                    .filter(|&k| !bvh2.nodes[kids[k]].is_leaf())
                    .max_by(|&i, &j| {
                        let area = |k: usize| bvh2.nodes[kids[k]].aabb().half_area();
                        area(i).total_cmp(&area(j))
                    });
                let Some(k) = open else { break };
                let first = bvh2.nodes[kids[k]].first_index as usize;
                kids[k] = first;
                kids.push(first + 1);
            }
            // slots: greedily the least cost (child, slot) pair first, cost = the child's centre
            // along slot s's direction
            let centre = node.aabb().center();
            let mut cost = Vec::with_capacity(kids.len() * 8);
            for (k, &kid) in kids.iter().enumerate() {
                let v = bvh2.nodes[kid].aabb().center() - centre;
                for slot in 0..8 {
                    let sign = |bit: usize| if slot & bit != 0 { -1.0 } else { 1.0 };
                    let dir = Vec3A::new(sign(4), sign(2), sign(1));
                    cost.push((v.dot(dir), k, slot));
                }
            }
            cost.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut slot_of = vec![usize::MAX; kids.len()];
            let mut taken = [false; 8];
            for (_, k, slot) in cost {
                if slot_of[k] == usize::MAX && !taken[slot] {
                    slot_of[k] = slot;
                    taken[slot] = true;
                }
            }
            // leaves into packs, first fit by decreasing size
            let mut leaves: Vec<usize> = (0..kids.len())
                .filter(|&k| bvh2.nodes[kids[k]].is_leaf())
                .collect();
            leaves.sort_by_key(|&k| std::cmp::Reverse(bvh2.nodes[kids[k]].prim_count));
            let first_pack = packs.len();
            let mut out = empty;
            let mut bounds = [[f32::INFINITY; 8], [f32::NEG_INFINITY; 8]].repeat(3);
            for k in leaves {
                let leaf = &bvh2.nodes[kids[k]];
                let count = leaf.prim_count.min(4) as usize;
                let fits = (first_pack..packs.len()).find(|&p| packs[p].used + count <= 4);
                let p = fits.unwrap_or_else(|| {
                    packs.push(PackBuilder::default());
                    packs.len() - 1
                });
                let lane = packs[p].used;
                let start = leaf.first_index as usize;
                for &prim in &bvh2.primitive_indices[start..start + count] {
                    packs[p].push(&tris[prim as usize], prim);
                }
                out.leaves |= 1 << slot_of[k];
                out.child[slot_of[k]] =
                    LEAF | (p as u32) << 4 | (lane as u32) << 2 | (count as u32 - 1);
            }
            for (k, &kid) in kids.iter().enumerate() {
                let aabb = bvh2.nodes[kid].aabb();
                let (lo, hi) = (aabb.min.to_array(), aabb.max.to_array());
                for axis in 0..3 {
                    bounds[2 * axis][slot_of[k]] = lo[axis] - pad;
                    bounds[2 * axis + 1][slot_of[k]] = hi[axis] + pad;
                }
                if !bvh2.nodes[kid].is_leaf() {
                    wide.nodes.push(empty);
                    out.child[slot_of[k]] = wide.nodes.len() as u32 - 1;
                    todo.push((kid, wide.nodes.len() - 1, depth + 1));
                }
            }
            out.bounds = [0, 1, 2, 3, 4, 5].map(|j| f32x8::new(bounds[j]));
            wide.nodes[w] = out;
        }
        wide.packs = packs.iter().map(PackBuilder::finish).collect();
        wide.stack_len = 7 * deepest + 8;
        wide
    }

    /// The number of nodes (eight children each).
    pub(crate) fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The number of triangles in the leaves (more than the scene's when spatial splits put one
    /// in several leaves).
    pub(crate) fn primitive_count(&self) -> usize {
        let lanes = |c: u32| ((c & 3) + 1) as usize;
        let leaves = self.nodes.iter().flat_map(|n| n.child.iter());
        leaves.filter(|&&c| c & LEAF != 0).map(|&c| lanes(c)).sum()
    }

    /// The number of node levels below the root.
    pub(crate) fn depth(&self) -> usize {
        (self.stack_len - 8) / 7
    }

    /// `"AVX"` when the traversals run their AVX versions, else `"SSE"`.
    pub(crate) fn node_test(&self) -> &'static str {
        if self.avx { "AVX" } else { "SSE" }
    }

    /// The number of four-triangle packs.
    pub(crate) fn pack_count(&self) -> usize {
        self.packs.len()
    }

    /// Asks for node `c`'s four cache lines.
    #[inline(always)]
    fn prefetch_node(&self, c: u32) {
        let child = &self.nodes[c as usize];
        prefetch(&child.bounds[0]);
        prefetch(&child.bounds[2]);
        prefetch(&child.bounds[4]);
        prefetch(&child.child);
    }

    /// Asks for the packs of `node`'s leaves in `mask` (three cache lines each).
    #[inline(always)]
    fn prefetch_leaves(&self, node: &Node8, mut mask: u32) {
        while mask != 0 {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            let pack = &self.packs[Self::leaf(node.child[i]).0];
            prefetch(&pack.v0[0]);
            prefetch(&pack.e1[1]);
            prefetch(&pack.prim);
        }
    }

    /// The pack and lane mask of leaf child `c`.
    #[inline(always)]
    fn leaf(c: u32) -> (usize, u32) {
        let (pack, lane, count) = (((c & !LEAF) >> 4) as usize, (c >> 2) & 3, (c & 3) + 1);
        (pack, ((1u32 << count) - 1) << lane)
    }

    /// The closest accepted hit of `ray` within `[ray.tmin, ray.tmax]`: `accept(primitive, t)` returns
    /// the hit's key (`t`, or `t` plus a tie margin; `∞` rejects it) and the least key wins.
    /// Returns the primitive and its key.
    pub(crate) fn closest(
        &self,
        ray: &Ray,
        accept: impl FnMut(u32, f32) -> f32,
    ) -> Option<(u32, f32)> {
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        if self.avx {
            // SAFETY: `avx` is set only where the CPU said it has AVX (`WideBvh::from_bvh2`)
            return unsafe { self.closest_avx(ray, accept) };
        }
        self.closest_by(ray, accept, Slab::test)
    }

    /// [`WideBvh::closest`] compiled for AVX, with [`Slab::test_avx`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn closest_avx(&self, ray: &Ray, accept: impl FnMut(u32, f32) -> f32) -> Option<(u32, f32)> {
        self.closest_by(ray, accept, |s: &Slab, n: &Node8, lo, hi| {
            s.test_avx(n, lo, hi)
        })
    }

    /// [`WideBvh::closest`] with the node test `test`.
    #[inline(always)]
    fn closest_by(
        &self,
        ray: &Ray,
        accept: impl FnMut(u32, f32) -> f32,
        test: impl Fn(&Slab, &Node8, f32, f32) -> ([f32; 8], u32),
    ) -> Option<(u32, f32)> {
        // the smallest stack that holds the tree's deepest path (zeroing one costs per query)
        if self.nodes.is_empty() {
            None
        } else if self.stack_len <= STACK / 4 {
            self.closest_with(&mut [(0, 0.0); STACK / 4], ray, accept, test)
        } else if self.stack_len <= STACK {
            self.closest_with(&mut [(0, 0.0); STACK], ray, accept, test)
        } else {
            self.closest_with(&mut vec![(0, 0.0); self.stack_len], ray, accept, test)
        }
    }

    /// [`WideBvh::closest`] with the given stack and node test.
    #[inline(always)]
    fn closest_with(
        &self,
        stack: &mut [(u32, f32)],
        ray: &Ray,
        mut accept: impl FnMut(u32, f32) -> f32,
        test: impl Fn(&Slab, &Node8, f32, f32) -> ([f32; 8], u32),
    ) -> Option<(u32, f32)> {
        let slab = Slab::new(ray);
        let (o, d) = (splat4(ray.origin), splat4(ray.direction));
        let mut tmax = ray.tmax;
        let mut best = None;
        let mut sp = 0;
        let mut at = 0u32;
        loop {
            let node = &self.nodes[at as usize];
            let (near, mask) = test(&slab, node, ray.tmin, tmax);
            let leaves = mask & node.leaves;
            // inner children pushed farthest deepest (the stack above `base` stays sorted by
            // entry distance, decreasing toward the top), their nodes and the leaves' packs
            // fetched while the leaves are tested
            let base = sp;
            let mut inner = mask & !node.leaves;
            while inner != 0 {
                let i = inner.trailing_zeros() as usize;
                inner &= inner - 1;
                let c = node.child[i];
                self.prefetch_node(c);
                let entry = (c, near[i]);
                let mut j = sp;
                while j > base && stack[j - 1].1 < entry.1 {
                    stack[j] = stack[j - 1];
                    j -= 1;
                }
                stack[j] = entry;
                sp += 1;
            }
            self.prefetch_leaves(node, leaves);
            // the leaves: a hit shortens the ray for the rest
            let mut leaves = leaves;
            while leaves != 0 {
                let i = leaves.trailing_zeros() as usize;
                leaves &= leaves - 1;
                let (p, m) = Self::leaf(node.child[i]);
                let pack = &self.packs[p];
                let (t, mut lanes) = pack.intersect(&o, &d, ray.tmin, tmax, m);
                while lanes != 0 {
                    let lane = lanes.trailing_zeros() as usize;
                    lanes &= lanes - 1;
                    let key = accept(pack.prim[lane], t[lane]);
                    if key < tmax {
                        tmax = key;
                        best = Some((pack.prim[lane], key));
                    }
                }
            }
            // the nearest pending node that may still hold a closer hit
            loop {
                if sp == 0 {
                    return best;
                }
                sp -= 1;
                if stack[sp].1 <= tmax {
                    at = stack[sp].0;
                    break;
                }
            }
        }
    }

    /// Whether any accepted hit lies within `[ray.tmin, ray.tmax]`: `accept(primitive, t)` says
    /// whether the geometric hit at `t` counts. Not nearest first (the boxes around the ray's
    /// origin all tie there, and a shadow ray from a surface in clutter then visits all of them
    /// before any leaf): as obvhs's traversal, a node's leaves are tested when it is visited, its
    /// inner children in the order the CWBVH build laid their slots out for the ray's octant
    /// (front to back by their centres' direction), which found occluders 1.6× sooner on
    /// `random-boxes-100000`'s surface rays.
    pub(crate) fn any(&self, ray: &Ray, accept: impl FnMut(u32, f32) -> bool) -> bool {
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        if self.avx {
            // SAFETY: `avx` is set only where the CPU said it has AVX (`WideBvh::from_bvh2`)
            return unsafe { self.any_avx(ray, accept) };
        }
        self.any_by(ray, accept, Slab::test)
    }

    /// [`WideBvh::any`] compiled for AVX, with [`Slab::test_avx`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn any_avx(&self, ray: &Ray, accept: impl FnMut(u32, f32) -> bool) -> bool {
        self.any_by(ray, accept, |s: &Slab, n: &Node8, lo, hi| {
            s.test_avx(n, lo, hi)
        })
    }

    /// [`WideBvh::any`] with the node test `test`.
    #[inline(always)]
    fn any_by(
        &self,
        ray: &Ray,
        accept: impl FnMut(u32, f32) -> bool,
        test: impl Fn(&Slab, &Node8, f32, f32) -> ([f32; 8], u32),
    ) -> bool {
        if self.nodes.is_empty() {
            false
        } else if self.stack_len <= STACK / 4 {
            self.any_with(&mut [0; STACK / 4], ray, accept, test)
        } else if self.stack_len <= STACK {
            self.any_with(&mut [0; STACK], ray, accept, test)
        } else {
            self.any_with(&mut vec![0; self.stack_len], ray, accept, test)
        }
    }

    /// [`WideBvh::any`] with the given stack and node test.
    #[inline(always)]
    fn any_with(
        &self,
        stack: &mut [u32],
        ray: &Ray,
        mut accept: impl FnMut(u32, f32) -> bool,
        test: impl Fn(&Slab, &Node8, f32, f32) -> ([f32; 8], u32),
    ) -> bool {
        let slab = Slab::new(ray);
        let (o, d) = (splat4(ray.origin), splat4(ray.direction));
        // obvhs's slot priority: slot i ^ octant, highest first
        let d3 = ray.direction;
        let octant = (usize::from(d3.x >= 0.0) << 2)
            | (usize::from(d3.y >= 0.0) << 1)
            | usize::from(d3.z >= 0.0);
        let mut sp = 0;
        let mut at = 0u32;
        loop {
            let node = &self.nodes[at as usize];
            let (_, mask) = test(&slab, node, ray.tmin, ray.tmax);
            // inner children pushed in reverse slot priority (the first on top), their nodes
            // and the leaves' packs fetched while the leaves are tested
            for k in 0..8 {
                let i = k ^ octant;
                if mask & !node.leaves & (1 << i) != 0 {
                    let c = node.child[i];
                    self.prefetch_node(c);
                    stack[sp] = c;
                    sp += 1;
                }
            }
            self.prefetch_leaves(node, mask & node.leaves);
            for k in (0..8).rev() {
                let i = k ^ octant;
                if mask & node.leaves & (1 << i) == 0 {
                    continue;
                }
                let (p, m) = Self::leaf(node.child[i]);
                let pack = &self.packs[p];
                let (t, mut lanes) = pack.intersect(&o, &d, ray.tmin, ray.tmax, m);
                while lanes != 0 {
                    let lane = lanes.trailing_zeros() as usize;
                    lanes &= lanes - 1;
                    if accept(pack.prim[lane], t[lane]) {
                        return true;
                    }
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            at = stack[sp];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2_from_tris};
    use rand::{Rng, SeedableRng};

    /// The 12 triangles of the box `lo`–`hi`.
    fn cuboid(lo: Vec3A, hi: Vec3A) -> Vec<Triangle> {
        let corner = |k: usize| {
            Vec3A::select(
                glam::BVec3A::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
                hi,
                lo,
            )
        };
        let quads = [
            [0, 1, 3, 2],
            [4, 6, 7, 5],
            [0, 4, 5, 1],
            [2, 3, 7, 6],
            [0, 2, 6, 4],
            [1, 5, 7, 3],
        ];
        (quads.iter())
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .map(|[a, b, c]| Triangle {
                v0: corner(a),
                v1: corner(b),
                v2: corner(c),
            })
            .collect()
    }

    /// `n` random boxes in the unit cube (clutter).
    fn boxes(n: usize) -> Vec<Triangle> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        (0..n)
            .flat_map(|_| {
                let lo = Vec3A::new(rng.random(), rng.random(), rng.random()) * 0.9;
                let size = Vec3A::new(rng.random(), rng.random(), rng.random()) * 0.1;
                cuboid(lo, lo + size)
            })
            .collect()
    }

    /// The six walls of the unit cube, each cut into `n × n` squares of two triangles, and a box
    /// in the room.
    fn room(n: usize) -> Vec<Triangle> {
        let mut tris = cuboid(Vec3A::splat(0.3), Vec3A::new(0.6, 0.5, 0.7));
        for axis in 0..3 {
            for side in [0.0, 1.0] {
                let at = |i: usize, j: usize| {
                    let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                    let mut p = [0.0; 3];
                    p[axis] = side;
                    p[(axis + 1) % 3] = u;
                    p[(axis + 2) % 3] = v;
                    Vec3A::from_array(p)
                };
                for i in 0..n {
                    for j in 0..n {
                        let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                        tris.push(Triangle {
                            v0: a,
                            v1: b,
                            v2: c,
                        });
                        tris.push(Triangle {
                            v0: a,
                            v1: c,
                            v2: d,
                        });
                    }
                }
            }
        }
        tris
    }

    /// Every closest hit and every occlusion answer of the traversal (the AVX one where the CPU
    /// has AVX, and the SSE one) equals a brute-force loop over all triangles with obvhs's `Triangle::intersect`: the same distance to the bit (the
    /// same triangle unless two share that distance), on clutter and on a tessellated room, with
    /// spatial splits (the default build) and without, from points inside and outside, with
    /// ranges that end before, at and after the hits.
    #[test]
    fn wide_traversal_matches_brute_force() {
        let cases = [
            (
                "random boxes",
                boxes(250),
                BvhBuildParams::very_slow_build(),
            ),
            (
                "tessellated room",
                room(15),
                BvhBuildParams::very_slow_build(),
            ),
            ("tessellated room", room(15), BvhBuildParams::medium_build()),
        ];
        for (seed, (name, tris, params)) in cases.into_iter().enumerate() {
            let lo = (tris.iter()).fold(Vec3A::INFINITY, |m, t| m.min(t.v0.min(t.v1).min(t.v2)));
            let hi =
                (tris.iter()).fold(Vec3A::NEG_INFINITY, |m, t| m.max(t.v0.max(t.v1).max(t.v2)));
            let params = BvhBuildParams {
                max_prims_per_leaf: 4,
                ..params
            };
            let bvh2 = build_bvh2_from_tris(&tris, params, &mut Default::default());
            let wide = WideBvh::from_bvh2(&bvh2, &tris);
            assert!(wide.primitive_count() >= tris.len());
            // the SSE traversal on this machine too: the same answers to the bit
            let sse = WideBvh {
                avx: false,
                ..wide.clone()
            };
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed as u64);
            let (mut hits, mut ties, mut blocked) = (0, 0, 0);
            for k in 0..5_000 {
                let mut p = || {
                    let u = Vec3A::new(rng.random(), rng.random(), rng.random());
                    lo - 0.2 * (hi - lo) + u * 1.4 * (hi - lo)
                };
                let (a, b) = (p(), p());
                let len = (b - a).length();
                let tmax = [f32::INFINITY, len, 0.3 * len][k % 3];
                let ray = Ray {
                    origin: a,
                    direction: (b - a) / len,
                    tmin: 0.0,
                    tmax,
                };
                let reference = obvhs::ray::Ray::new(a, ray.direction, 0.0, tmax);
                let brute = (0..tris.len())
                    .map(|i| (i as u32, tris[i].intersect(&reference)))
                    .filter(|x| x.1.is_finite())
                    .min_by(|x, y| x.1.total_cmp(&y.1));
                let ours = wide.closest(&ray, |_, t| t);
                assert_eq!(sse.closest(&ray, |_, t| t), ours, "{name} ray {k}");
                assert_eq!(ours.is_some(), brute.is_some(), "{name} ray {k}");
                if let (Some((face, t)), Some((theirs, t_brute))) = (ours, brute) {
                    hits += 1;
                    assert_eq!(t.to_bits(), t_brute.to_bits(), "{name} ray {k}");
                    if face != theirs {
                        ties += 1;
                        let t2 = tris[face as usize].intersect(&reference);
                        assert_eq!(t2.to_bits(), t.to_bits(), "{name} ray {k}");
                    }
                }
                let occluded = wide.any(&ray, |_, _| true);
                assert_eq!(sse.any(&ray, |_, _| true), occluded, "{name} ray {k}");
                assert_eq!(occluded, brute.is_some(), "{name} ray {k}");
                blocked += usize::from(occluded);
                // a filter that refuses the nearest face: the next one is found
                if let Some((first, _)) = brute {
                    let second = (0..tris.len())
                        .filter(|&i| i as u32 != first)
                        .map(|i| tris[i].intersect(&reference))
                        .filter(|t| t.is_finite())
                        .min_by(f32::total_cmp);
                    let ours =
                        wide.closest(&ray, |f, t| if f == first { f32::INFINITY } else { t });
                    assert_eq!(
                        ours.map(|x| x.1.to_bits()),
                        second.map(f32::to_bits),
                        "{name} ray {k}"
                    );
                    let any = wide.any(&ray, |f, _| f != first);
                    assert_eq!(any, second.is_some(), "{name} ray {k}");
                }
            }
            // the rays meet geometry often and miss it often
            assert!(hits > 1_000 && blocked < 4_900, "{name}: {hits} {blocked}");
            assert!(ties < 10, "{name}: {ties}");
        }
    }
}
