#include "apps/inspector/GraphFile.h"

namespace loom::inspector {

namespace fs = std::filesystem;

std::string saveGraphChecked(const RenderGraph& graph, const std::string& path) {
    try {
        graph.save(path);
        auto back = RenderGraph::load(path);
        if (!back->equals(graph))
            return path + ": the saved graph does not load back equal (round trip failed)";
        return "";
    } catch (const std::exception& e) {
        return e.what();
    }
}

FileWatcher::FileWatcher(std::string path) : mPath(std::move(path)) {
    std::error_code ec;
    mTime = fs::last_write_time(mPath, ec);
    mSize = fs::file_size(mPath, ec);
}

bool FileWatcher::changed() {
    if (mPath.empty()) return false;
    std::error_code ec, ec2;
    auto t = fs::last_write_time(mPath, ec);
    auto s = fs::file_size(mPath, ec2);
    if (ec || ec2) return false;  // mid-save (editors replace files): look again later
    if (t == mTime && s == mSize) return false;
    mTime = t;
    mSize = s;
    return true;
}

}  // namespace loom::inspector
