#include "apps/inspector/MemoryTable.h"

#include "core/util/Log.h"

namespace loom::inspector {

namespace {
std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
}
// The pass a resource belongs to: "node" of node.port, node#persistent, node.port@prev.
std::string ownerOf(const std::string& name) {
    return name.substr(0, name.find_first_of(".#"));
}
}  // namespace

MemoryTable memoryTable(const MemoryReport& report, const std::string& selectedPass,
                        bool aliasing) {
    MemoryTable t;
    for (const auto& m : report.resources) {
        MemoryRow r;
        r.name = m.name;
        r.kind = m.kind == ResourceKind::Texture ? "texture" : "buffer";
        r.size = m.kind == ResourceKind::Texture
                     ? fmt::format("{} {}x{}", m.format, m.width, m.height)
                     : formatBytes(m.bytes);
        r.bytes = formatBytes(m.bytes);
        r.lifetime = lifetimeName(m.lifetime);
        if (!m.inPlace.empty()) r.shares = "in place: " + join(m.inPlace);
        if (!m.aliasedWith.empty())
            r.shares +=
                (r.shares.empty() ? "" : "; ") + std::string("aliased: ") + join(m.aliasedWith);
        r.ofSelectedPass = !selectedPass.empty() && ownerOf(m.name) == selectedPass;
        t.rows.push_back(std::move(r));
    }
    // The inspector renders with aliasing off so that every port stays viewable.
    t.summary =
        fmt::format("{} resources: {} allocated, {} without aliasing{}", report.resources.size(),
                    formatBytes(report.allocatedBytes), formatBytes(report.unaliasedBytes),
                    aliasing ? "" : " (aliasing off in the inspector)");
    return t;
}

}  // namespace loom::inspector
