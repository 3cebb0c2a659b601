//! PLACEHOLDER — owned by the USD helper; replaced wholesale.
