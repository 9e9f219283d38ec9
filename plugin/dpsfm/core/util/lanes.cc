#include "dpsfm/core/util/lanes.h"

namespace dpsfm {

DPSFM_VECTOR_CLONES double DotInLanes(const float* a,
                                      const float* b,
                                      size_t count) {
  return DotInLanesOf<Lanes>(a, b, count);
}

}  // namespace dpsfm
