// Per-resource memory of a compiled graph, shared by `loom render --timings` and the inspector.
#include <algorithm>

#include "core/graph/RenderGraph.h"
#include "core/util/Log.h"

namespace loom {

const char* lifetimeName(ResourceMemory::Lifetime l) {
    switch (l) {
        case ResourceMemory::Lifetime::Transient:
            return "transient";
        case ResourceMemory::Lifetime::Output:
            return "output";
        case ResourceMemory::Lifetime::Scratch:
            return "scratch";
        case ResourceMemory::Lifetime::Persistent:
            return "persistent";
        case ResourceMemory::Lifetime::History:
            return "history";
    }
    return "?";
}

MemoryReport memoryReport(const CompiledGraph& cg) {
    MemoryReport rep;
    std::vector<uint64_t> physicalBytes(cg.physicalCount, 0);
    for (const auto& r : cg.resources) {
        ResourceMemory m;
        m.name = r.name;
        m.kind = r.kind;
        if (r.kind == ResourceKind::Texture) {
            m.format = gpu::formatName(r.format);
            m.width = r.width;
            m.height = r.height;
            m.bytes = uint64_t(r.width) * r.height * gpu::bytesPerTexel(r.format);
        } else {
            m.bytes = r.bytes;
        }
        m.lifetime = r.historyOf >= 0 ? ResourceMemory::Lifetime::History
                     : r.persistent   ? ResourceMemory::Lifetime::Persistent
                     : r.scratch      ? ResourceMemory::Lifetime::Scratch
                     : r.graphOutput  ? ResourceMemory::Lifetime::Output
                                      : ResourceMemory::Lifetime::Transient;
        m.physical = r.physical;
        m.inPlace = r.inPlaceWriters;
        for (const auto& o : cg.resources)
            if (&o != &r && o.physical == r.physical) m.aliasedWith.push_back(o.name);
        if (r.physical >= 0 && r.physical < cg.physicalCount)
            physicalBytes[r.physical] = std::max(physicalBytes[r.physical], m.bytes);
        rep.unaliasedBytes += m.bytes;
        rep.resources.push_back(std::move(m));
    }
    for (uint64_t b : physicalBytes) rep.allocatedBytes += b;
    return rep;
}

std::string formatBytes(uint64_t bytes) {
    if (bytes >= (uint64_t(1) << 20)) return fmt::format("{:.1f} MiB", double(bytes) / (1 << 20));
    if (bytes >= 1024) return fmt::format("{:.1f} KiB", double(bytes) / 1024);
    return fmt::format("{} B", bytes);
}

std::string formatMemoryReport(const MemoryReport& report) {
    auto join = [](const std::vector<std::string>& v) {
        std::string s;
        for (auto& x : v) s += (s.empty() ? "" : ", ") + x;
        return s;
    };
    size_t nameW = 8;
    for (auto& m : report.resources) nameW = std::max(nameW, m.name.size());
    std::string out = fmt::format("{:<{}}  {:<7}  {:<20}  {:>10}  {:<10}  {}\n", "resource", nameW,
                                  "kind", "format/size", "bytes", "lifetime", "shares memory with");
    for (auto& m : report.resources) {
        std::string size = m.kind == ResourceKind::Texture
                               ? fmt::format("{} {}x{}", m.format, m.width, m.height)
                               : formatBytes(m.bytes);
        std::string shares;
        if (!m.inPlace.empty()) shares = "in place: " + join(m.inPlace);
        if (!m.aliasedWith.empty())
            shares += (shares.empty() ? "" : "; ") + std::string("aliased: ") + join(m.aliasedWith);
        out += fmt::format("{:<{}}  {:<7}  {:<20}  {:>10}  {:<10}  {}\n", m.name, nameW,
                           m.kind == ResourceKind::Texture ? "texture" : "buffer", size, m.bytes,
                           lifetimeName(m.lifetime), shares.empty() ? "-" : shares);
    }
    out += fmt::format(
        "{} resources in {} allocations: {} allocated, {} without aliasing\n",
        report.resources.size(),
        [&] {
            std::vector<int> p;
            for (auto& m : report.resources)
                if (std::find(p.begin(), p.end(), m.physical) == p.end()) p.push_back(m.physical);
            return p.size();
        }(),
        formatBytes(report.allocatedBytes), formatBytes(report.unaliasedBytes));
    return out;
}

MemoryReport RenderGraph::memoryReport() const {
    return mCompiled ? loom::memoryReport(*mCompiled) : MemoryReport{};
}

}  // namespace loom
