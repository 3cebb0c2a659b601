//! PLACEHOLDER — owned by the BVH helper; replaced wholesale.
