# Places the point labels of a log-log gnuplot plot so that they overlap
# neither each other nor any point (bench/speed_error.sh's speed-against-error
# plot, where methods of similar speed and error sit close together).
#
# Input: lines "GROUP LABEL X Y" (X, Y > 0). Variables (-v): the terminal size
# W, H in pixels; the plot area's margins as screen fractions lm, rm, bm, tm
# (gnuplot's `set lmargin at screen lm` ...); the axis ranges xmin, xmax,
# ymin, ymax; cw, ch: a label character's width and the label's height in
# pixels (a little above what the font draws).
# Output: "GROUP LABEL LX LY X0 Y0 X1 Y1" per point: the label's left end,
# vertically centred (gnuplot `with labels left`), at data coordinates LX, LY;
# X0 Y0 X1 Y1 a leader line from the point to the label, or "- - - -" when the
# label sits next to its point. Greedy, the most crowded points first: each
# label takes the first free place of 8 around its point (right, left, above,
# below, the diagonals), else the same farther out (4 more rings) with a leader
# line; where none is free, the place that overlaps least.
function sx(x) { return W * (lm + (rm - lm) * (log(x) - log(xmin)) / (log(xmax) - log(xmin))) }
function sy(y) { return H * (1 - (bm + (tm - bm) * (log(y) - log(ymin)) / (log(ymax) - log(ymin)))) }
function dx(p) { return exp(log(xmin) + (p / W - lm) / (rm - lm) * (log(xmax) - log(xmin))) }
function dy(p) { return exp(log(ymin) + ((1 - p / H) - bm) / (tm - bm) * (log(ymax) - log(ymin))) }
function overlap(a0, a1, b0, b1) { return (a1 < b0 || b1 < a0) ? 0 : (a1 < b1 ? a1 : b1) - (a0 > b0 ? a0 : b0) }
# How much the box (x0, y0)-(x1, y1) collides: area over placed labels, points and outside the plot.
function cost(x0, y0, x1, y1,    c, j, ox, oy) {
  c = 0
  if (x0 < lm * W || x1 > rm * W || y0 < (1 - tm) * H || y1 > (1 - bm) * H) c += 1e6
  for (j = 1; j <= placed; ++j) {
    ox = overlap(x0 - 2, x1 + 2, bx0[j], bx1[j]); oy = overlap(y0 - 1, y1 + 1, by0[j], by1[j])
    if (ox > 0 && oy > 0) c += ox * oy + 1000
  }
  for (j = 1; j <= n; ++j) {
    ox = overlap(x0, x1, px[j] - r, px[j] + r); oy = overlap(y0, y1, py[j] - r, py[j] + r)
    if (ox > 0 && oy > 0) c += ox * oy + 1000
  }
  return c
}
{ ++n; group[n] = $1; label[n] = $2; px[n] = sx($3); py[n] = sy($4) }
END {
  r = 6  # a point's half size, pixels
  # Directions: right, left, up, down, then the diagonals (screen y down).
  split("1 -1 0 0 1 1 -1 -1", ux, " "); split("0 0 -1 1 -1 1 -1 1", uy, " ")
  nring = split("9 26 46 70 100", ring, " ")
  # Crowded points first: they have the fewest free places.
  for (i = 1; i <= n; ++i) {
    crowd[i] = 0
    for (j = 1; j <= n; ++j) crowd[i] += (px[i] - px[j]) ^ 2 + (py[i] - py[j]) ^ 2 < 120 ^ 2
    order[i] = i
  }
  for (i = 2; i <= n; ++i)
    for (j = i; j > 1 && crowd[order[j]] > crowd[order[j - 1]]; --j) { t = order[j]; order[j] = order[j - 1]; order[j - 1] = t }
  for (o = 1; o <= n; ++o) {
    i = order[o]
    w = length(label[i]) * cw; h = ch
    best_cost = -1
    for (k = 1; k <= nring && best_cost != 0; ++k) {
      gap = ring[k]
      for (d = 1; d <= 8 && best_cost != 0; ++d) {
        # Beside the point along each nonzero direction, centred on it along the other axis.
        if (ux[d] > 0) x0 = px[i] + gap; else if (ux[d] < 0) x0 = px[i] - gap - w; else x0 = px[i] - w / 2
        g = ux[d] ? 0.6 * gap : gap
        if (uy[d] > 0) y0 = py[i] + g; else if (uy[d] < 0) y0 = py[i] - g - h; else y0 = py[i] - h / 2
        c = cost(x0, y0, x0 + w, y0 + h)
        if (best_cost < 0 || c < best_cost) { best_cost = c; bx = x0; by = y0; bk = k }
      }
    }
    ++placed; bx0[placed] = bx; bx1[placed] = bx + w; by0[placed] = by; by1[placed] = by + h
    lead = "- - - -"
    if (bk > 1) {
      # From the point to the nearest point of the box.
      ex = px[i] < bx ? bx : (px[i] > bx + w ? bx + w : px[i])
      ey = py[i] < by ? by : (py[i] > by + h ? by + h : py[i])
      lead = sprintf("%.6g %.6g %.6g %.6g", dx(px[i]), dy(py[i]), dx(ex), dy(ey))
    }
    line[i] = sprintf("%s %s %.6g %.6g %s", group[i], label[i], dx(bx), dy(by + h / 2), lead)
  }
  for (i = 1; i <= n; ++i) print line[i]
}
