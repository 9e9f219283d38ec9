// Sampled curves: geometric grids of nodes and the minimum of a sampled curve.
// (Sample statistics live in statistics.h.)
#pragma once

#include <cstddef>
#include <vector>

namespace dpsfm {

// Nodes lo, lo r, lo r^2, ... below hi, then hi itself (lo < hi, r > 1): a
// grid whose spacing does not change when the range is extended, so the
// nodes inside the old range stay where they were.
std::vector<double> GeometricNodes(double lo, double hi, double ratio);

// Minimiser of a curve sampled at increasing xs: the vertex of the parabola
// through the lowest sample and its two neighbours, clamped to them; the
// lowest sample itself at either end or where the three are not convex.
// *index (optional) receives the lowest sample's index.
double CurveMinimum(const std::vector<double>& xs,
                    const std::vector<double>& ys,
                    size_t* index);

}  // namespace dpsfm
