#!/usr/bin/env python3
"""bench/lib/place_labels.awk: on a crowded speed-against-error plot (the
methods of scene 1 as bench/speed_error.sh measured them, and two more scenes
near them), no two labels overlap, no label covers a point, and every label
is inside the plot area. Checked in pixels from the awk's output, with the
plot geometry written out here as speed_error.sh sets it."""
import math
import subprocess
import sys

W, H = 1280, 800  # speed_error.sh's size for more than 20 points
LM, RM, BM, TM = 0.09, 0.84, 0.11, 0.92
CW, CH = 6.5, 13.0
POINT_HALF = 4.0  # pixels: a gnuplot point

SCENE1 = [("noisy", 0.754, 2.47693), ("accumulate", 5.740, 0.690216), ("atrous", 613.202, 0.199738),
          ("svgf", 113.595, 0.189778), ("svgf-fb", 211.511, 0.169183), ("reflect", 628.246, 0.10477),
          ("stat-temporal", 847.057, 0.536803), ("progressive", 65.682, 0.551426),
          ("svgf-split", 136.121, 0.215777), ("stat-temporal-r6", 125.887, 0.546951),
          ("reflect-nospec", 166.969, 0.134841)]


def main():
    awk_script = sys.argv[1]
    points = []
    for scene, (time_scale, error_scale) in ((1, (1.0, 1.0)), (2, (0.9, 1.3)), (3, (1.15, 0.8))):
        points += [(scene, name, t * time_scale, e * error_scale) for name, t, e in SCENE1]
    f = 10 ** 0.2  # a fifth of a decade around the data, as speed_error.sh
    xmin, xmax = min(p[2] for p in points) / f, max(p[2] for p in points) * f
    ymin, ymax = min(p[3] for p in points) / f, max(p[3] for p in points) * f

    def sx(x):
        return W * (LM + (RM - LM) * (math.log(x) - math.log(xmin)) / (math.log(xmax) - math.log(xmin)))

    def sy(y):
        return H * (1 - (BM + (TM - BM) * (math.log(y) - math.log(ymin)) / (math.log(ymax) - math.log(ymin))))

    text = "".join("%d %s %.6g %.6g\n" % p for p in points)
    out = subprocess.run(["awk", "-v", "W=%d" % W, "-v", "H=%d" % H, "-v", "lm=%g" % LM, "-v", "rm=%g" % RM,
                          "-v", "bm=%g" % BM, "-v", "tm=%g" % TM, "-v", "xmin=%.6g" % xmin, "-v", "xmax=%.6g" % xmax,
                          "-v", "ymin=%.6g" % ymin, "-v", "ymax=%.6g" % ymax, "-v", "cw=%g" % CW, "-v", "ch=%g" % CH,
                          "-f", awk_script], input=text, capture_output=True, text=True, check=True).stdout
    boxes = []
    for line in out.splitlines():
        group, label, lx, ly = line.split()[:4]
        x0, yc = sx(float(lx)), sy(float(ly))
        boxes.append((group + ":" + label, x0, yc - CH / 2, x0 + len(label) * CW, yc + CH / 2))
    if len(boxes) != len(points):
        print("FAIL: %d labels for %d points" % (len(boxes), len(points)))
        return 1
    problems = []
    eps = 0.5  # boxes may touch (rounding of the awk's 6-digit output)
    for i, a in enumerate(boxes):
        if a[1] < LM * W - eps or a[3] > RM * W + eps or a[2] < (1 - TM) * H - eps or a[4] > (1 - BM) * H + eps:
            problems.append("%s outside the plot area" % a[0])
        for b in boxes[i + 1:]:
            if a[1] < b[3] - eps and b[1] < a[3] - eps and a[2] < b[4] - eps and b[2] < a[4] - eps:
                problems.append("%s overlaps %s" % (a[0], b[0]))
        for scene, name, t, e in points:
            px, py = sx(t), sy(e)
            if a[1] < px + POINT_HALF and px - POINT_HALF < a[3] and a[2] < py + POINT_HALF and py - POINT_HALF < a[4]:
                problems.append("%s covers the point of %d:%s" % (a[0], scene, name))
    for p in problems:
        print("FAIL: " + p)
    print("%d labels, %d problems" % (len(boxes), len(problems)))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
