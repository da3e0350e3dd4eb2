// The breakable-object scene (demos/, issue #4) run with one collision pipeline, as a results record.
#pragma once

#include "RunArgs.h"

#include <nlohmann/json.hpp>

namespace cullide::bench {

/// engine: cullide | bullet-dbvt | bullet-sap. Fills the record's timing, stage and error fields.
void runBreakable(const RunArgs& args, nlohmann::json& record);

}  // namespace cullide::bench
