//! PLACEHOLDER — owned by the output helper; replaced wholesale.
