// What stat_prepare tells stat_filter about pixel p in variance.w
// (docs/pipelines.md, "stat" and "stat-temporal").
#ifndef DN_STAT_CLASS_GLSL
#define DN_STAT_CLASS_GLSL

// Its neighbours are tested by the symmetric Welch test.
const float DN_STAT_TESTED = 0.0;
// It moves (stat-temporal): its neighbours are tested by Eq. 14, as their
// histories may hold what moved over them.
const float DN_STAT_MOVING = 1.0;
// A still pixel the guides do not explain (stat-temporal): it shows the mean
// of its own samples and gathers nothing.
const float DN_STAT_KEPT = 2.0;
// Tested as DN_STAT_TESTED, with its 3x3 window's variance (pool_single: it
// has fewer than 2 samples); its theta.w counts the window's samples, not its own.
const float DN_STAT_POOLED = 3.0;

#endif
