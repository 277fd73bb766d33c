#pragma once
// The inspector's Memory tab as data: one row per graph resource from
// RenderGraph::memoryReport() (the report `loom render --timings` prints), with the rows of the
// selected pass marked. Window-free: unit-tested in tests/unit/test_inspector_memory.cpp.
#include <string>
#include <vector>

#include "core/graph/RenderGraph.h"

namespace loom::inspector {

struct MemoryRow {
    std::string name, kind, size, bytes, lifetime, shares;  // shares: aliasing / in place
    bool ofSelectedPass = false;  // the resource belongs to the selected pass
};

struct MemoryTable {
    std::vector<MemoryRow> rows;
    std::string summary;  // totals: allocated vs without aliasing
};

MemoryTable memoryTable(const MemoryReport& report, const std::string& selectedPass, bool aliasing);

}  // namespace loom::inspector
