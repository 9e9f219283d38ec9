#include "dpsfm/core/util/lanes.h"

namespace dpsfm {

DPSFM_VECTOR_CLONES double DotInLanes(const float* a,
                                      const float* b,
                                      size_t count) {
  // Two sets of lanes, eight values a step: one set's additions would wait
  // on each other.
  Lanes low{}, high{};
  size_t i = 0;
  for (; i + 8 <= count; i += 8) {
    Lanes u, v;
    LoadLanes(a + i, &u);
    LoadLanes(b + i, &v);
    low += u * v;
    LoadLanes(a + i + 4, &u);
    LoadLanes(b + i + 4, &v);
    high += u * v;
  }
  for (; i < count; ++i) low[0] += static_cast<double>(a[i]) * b[i];
  return LanesTotal(low + high);
}

}  // namespace dpsfm
