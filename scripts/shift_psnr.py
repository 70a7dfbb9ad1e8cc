#!/usr/bin/env python3
"""The PSNR of a photo against itself moved by a fraction of a pixel: what a camera pose that is
off by that much costs a test view, whatever the model (docs/captures.md, the paragraph
"Camera-pose refinement is not built").

usage: shift_psnr.py SHIFT_PX WIDTH PHOTO...   (pip install pillow)

Each photo is area-downscaled to WIDTH (the training size) and compared with itself moved by
SHIFT_PX pixels along x and along y, bilinearly, to first order: the mean squared difference to
its right and lower neighbours times SHIFT_PX squared, averaged over the two directions.
"""
import math
import sys

from PIL import Image


def shift_psnr(path, shift, width):
    try:
        image = Image.open(path).convert("RGB")
    except OSError as e:
        sys.exit(f"{path}: expected a photo Pillow can read ({e})")
    height = round(image.height * width / image.width)
    pixels = image.resize((width, height), Image.BOX).load()
    total, count = 0.0, 0
    for y in range(height - 1):
        for x in range(width - 1):
            here, right, below = pixels[x, y], pixels[x + 1, y], pixels[x, y + 1]
            for c in range(3):
                total += ((right[c] - here[c]) ** 2 + (below[c] - here[c]) ** 2) / 2
                count += 1
    mse = shift * shift * total / max(count, 1) / (255.0 * 255.0)
    # A flat photo (or no shift) looks the same moved: no error at all.
    return math.inf if mse == 0.0 else 10.0 * math.log10(1.0 / mse)


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    try:
        shift, width = float(sys.argv[1]), int(sys.argv[2])
    except ValueError:
        sys.exit(f"expected a shift in pixels and a whole width, got {sys.argv[1]!r} {sys.argv[2]!r}")
    if width < 2:
        sys.exit(f"expected a width of 2 pixels or more, got {width}")
    for path in sys.argv[3:]:
        print(f"{path}: moved by {shift} px at {width} px wide, {shift_psnr(path, shift, width):.2f} dB")


if __name__ == "__main__":
    main()
