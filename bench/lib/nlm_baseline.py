#!/usr/bin/env python3
"""OpenCV's non-local means on the tone-mapped frame, the baseline of
bench/image_quality.sh: the noisy RGB EXR is tone-mapped with Reinhard
x / (1 + x) and sRGB-encoded to 16 bits (8 bits lose the highlights: one
8-bit step near white is a factor of several in radiance), each channel
denoised by cv2.fastNlMeansDenoising (L1 norm, the 16-bit form), and mapped
back to linear radiance. The filter strength h is chosen per frame from
H_VALUES (in 8-bit steps) by the lowest linear RMSE against the reference:
an oracle choice, non-local means at its best.

usage: nlm_baseline.py NOISY.exr REFERENCE.exr OUT.exr   (prints the h chosen)
"""
import os
import sys

os.environ.setdefault("OPENCV_IO_ENABLE_OPENEXR", "1")
import cv2  # noqa: E402
import numpy as np  # noqa: E402

H_VALUES = (2, 3, 5, 8, 12, 18, 27, 40)


def srgb_encode(x):
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 0.0031308), 1 / 2.4) - 0.055)


def srgb_decode(x):
    return np.where(x <= 0.04045, x / 12.92, np.power((x + 0.055) / 1.055, 2.4))


LEVELS = 65535.0


def to_ldr(hdr):
    hdr = np.nan_to_num(np.maximum(hdr.astype(np.float64), 0.0), nan=0.0, posinf=0.0)
    return np.clip(np.rint(srgb_encode(hdr / (1.0 + hdr)) * LEVELS), 0, LEVELS).astype(np.uint16)


def to_hdr(ldr):
    t = np.minimum(srgb_decode(ldr.astype(np.float64) / LEVELS), (LEVELS - 1.0) / LEVELS)  # keep x / (1 + x) invertible
    return (t / (1.0 - t)).astype(np.float32)


def nlm(ldr, h):
    return np.dstack([cv2.fastNlMeansDenoising(np.ascontiguousarray(ldr[:, :, c]), h=[h * 257.0], templateWindowSize=7,
                                               searchWindowSize=21, normType=cv2.NORM_L1) for c in range(3)])


def main():
    noisy_path, ref_path, out_path = sys.argv[1:4]
    noisy = cv2.imread(noisy_path, cv2.IMREAD_UNCHANGED)[:, :, :3]
    ref = cv2.imread(ref_path, cv2.IMREAD_UNCHANGED)[:, :, :3].astype(np.float64)
    ldr = to_ldr(noisy)
    best = None
    for h in H_VALUES:
        out = to_hdr(nlm(ldr, h))
        err = float(np.sqrt(np.mean((out.astype(np.float64) - ref) ** 2)))
        if best is None or err < best[0]:
            best = (err, h, out)
    cv2.imwrite(out_path, best[2])
    print(best[1])


if __name__ == "__main__":
    main()
