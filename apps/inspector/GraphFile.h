#pragma once
// Graph files on disk for the inspector: saving edited graphs through the core's JSON (with a
// round-trip check) and watching files for hot reload. Window-free, unit-tested.
#include <filesystem>
#include <string>

#include "core/graph/RenderGraph.h"

namespace loom::inspector {

// Writes the graph (parameters included) with RenderGraph::save, loads the file back and
// checks it equals the graph. Returns "" or the error message; never throws.
std::string saveGraphChecked(const RenderGraph& graph, const std::string& path);

// Polls a file's modification time and size; changed() is true once per change.
class FileWatcher {
public:
    FileWatcher() = default;
    explicit FileWatcher(std::string path);
    bool changed();
    const std::string& path() const { return mPath; }

private:
    std::string mPath;
    std::filesystem::file_time_type mTime{};
    uintmax_t mSize = 0;
};

}  // namespace loom::inspector
