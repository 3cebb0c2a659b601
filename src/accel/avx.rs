//! The 8-wide node test of the BVH in one AVX pass (x86-64, chosen at run time with
//! `is_x86_feature_detected!("avx")`; other machines keep the two 4-wide halves of
//! `bvh.rs`). It performs the same operations, in the same order, as the 4-wide test
//! (the conservative slab test of PBR 4ed §6.1.2 and §6.8.2, widened as `RayBoxes` describes),
//! lane by lane, so both give the same mask and the same entry distances, bit for bit.
//!
//! The functions are `unsafe` and `#[inline(always)]` without `#[target_feature]`: they are
//! inlined into the traversal, which `Bvh` compiles with `#[target_feature(enable = "avx")]`
//! and calls only on a CPU with AVX (the pattern of the memchr crate's vector kernels; a
//! `#[target_feature]` function itself cannot be forced inline and stayed a call).
#![allow(unsafe_code)]

use std::arch::x86_64::{
    __m256, _mm256_add_ps, _mm256_cmp_ps, _mm256_loadu_ps, _mm256_max_ps, _mm256_min_ps,
    _mm256_movemask_ps, _mm256_mul_ps, _mm256_set1_ps, _mm256_setzero_ps, _mm256_storeu_ps,
    _mm256_sub_ps, _CMP_LE_OQ,
};

use super::bvh::{RayBoxes, WideNode, ENTER_SCALE, EXIT_SCALE};

/// Mask of the children (bit = slot) whose boxes the ray meets within [0, t_max], and the
/// widened entry distance of each slot.
///
/// # Safety
/// The CPU must run AVX.
#[inline(always)]
pub(super) unsafe fn intersect_node(
    node: &WideNode,
    ray: &RayBoxes,
    t_max: f32,
) -> (u32, [f32; 8]) {
    let near = |k: usize| slab(node, ray.near[k], ray.o_near[k].x, ray.inv_near[k].x);
    let far = |k: usize| slab(node, ray.far[k], ray.o_far[k].x, ray.inv_far[k].x);
    let enter = _mm256_max_ps(_mm256_max_ps(near(0), near(1)), near(2));
    let exit = _mm256_min_ps(_mm256_min_ps(far(0), far(1)), far(2));
    let margin = _mm256_set1_ps(f32::MIN_POSITIVE);
    let scaled = _mm256_mul_ps(enter, _mm256_set1_ps(ENTER_SCALE));
    let t_enter = _mm256_max_ps(_mm256_sub_ps(scaled, margin), _mm256_setzero_ps());
    let scaled = _mm256_mul_ps(exit, _mm256_set1_ps(EXIT_SCALE));
    let t_exit = _mm256_min_ps(_mm256_add_ps(scaled, margin), _mm256_set1_ps(t_max));
    let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t_enter, t_exit)) as u32;
    let mut out = [0.0; 8];
    _mm256_storeu_ps(out.as_mut_ptr(), t_enter);
    (mask & node.present as u32, out)
}

/// Distances `(plane − o)·inv` to the eight planes of row `row`.
///
/// # Safety
/// The CPU must run AVX.
#[inline(always)]
unsafe fn slab(node: &WideNode, row: usize, o: f32, inv: f32) -> __m256 {
    // A plane row is two Vec4: eight contiguous f32.
    let planes = _mm256_loadu_ps(node.planes[row].as_ptr().cast());
    _mm256_mul_ps(
        _mm256_sub_ps(planes, _mm256_set1_ps(o)),
        _mm256_set1_ps(inv),
    )
}
