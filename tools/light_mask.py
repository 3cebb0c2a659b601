"""The pixels away from a directly visible light, as every comparison in tools/ masks them."""

import numpy as np


def emitter_mask(img):
    """True away from the directly visible light (pixels > 5 grown by 2 px)."""
    bright = img.max(axis=-1) > 5.0
    grown = bright.copy()
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            grown |= np.roll(np.roll(bright, dy, 0), dx, 1)
    return ~grown
