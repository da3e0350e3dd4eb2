#include "cullide/Result.h"

namespace cullide {

void Result::clear() {
    pcs.clear();
    pairs.clear();
    pcsTriangles.clear();
    rejected.clear();
    stats = Stats{};
}

}  // namespace cullide
