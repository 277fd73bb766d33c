#include "core/util/AtomicFile.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/util/Error.h"

namespace loom {

namespace fs = std::filesystem;

namespace {

std::string errnoText(int e) {
    return std::strerror(e);
}

bool isSpecialFile(const std::string& path) {
    struct stat st;
    return ::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode);
}

std::string tempPathFor(const std::string& path) {
    static std::atomic<unsigned> counter{0};
    fs::path p(path);
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on the one-line sum.
    std::string name(1, '.');
    name += p.stem().string();
    name += ".tmp";
    name += std::to_string(::getpid());
    name += '-';
    name += std::to_string(counter++);
    name += p.extension().string();
    return (p.parent_path() / name).string();
}

void makeParent(const std::string& path, const std::string& what) {
    fs::path parent = fs::path(path).parent_path();
    if (parent.empty()) return;
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec)
        throw UserError(path + ": cannot create the directory of this " + what + ": " +
                        ec.message());
}

}  // namespace

void writeFileAtomic(const std::string& path, const std::string& what,
                     const std::function<void(const std::string& tmpPath)>& write) {
    if (path.empty()) throw UserError("empty path for a " + what);
    if (fs::is_directory(path)) throw UserError(path + ": is a directory, not a " + what);
    if (isSpecialFile(path)) {
        write(path);
        return;
    }
    makeParent(path, what);
    std::string tmp = tempPathFor(path);
    try {
        write(tmp);
        // The data must be on disk before the rename makes it the file.
        int fd = ::open(tmp.c_str(), O_RDONLY);
        if (fd < 0 || ::fsync(fd) != 0) {
            int e = errno;
            if (fd >= 0) ::close(fd);
            throw UserError(path + ": cannot write " + what + ": " + errnoText(e));
        }
        ::close(fd);
        if (::rename(tmp.c_str(), path.c_str()) != 0)
            throw UserError(path + ": cannot replace the " + what + ": " + errnoText(errno));
    } catch (...) {
        std::remove(tmp.c_str());
        throw;
    }
}

void writeTextFileAtomic(const std::string& path, const std::string& what,
                         const std::string& content) {
    writeFileAtomic(path, what, [&](const std::string& tmp) {
        std::FILE* f = std::fopen(tmp.c_str(), "wb");
        if (!f)
            throw UserError(path + ": cannot open " + what + " for writing: " + errnoText(errno));
        errno = 0;
        bool ok = std::fwrite(content.data(), 1, content.size(), f) == content.size();
        ok = std::fflush(f) == 0 && ok;
        int e = errno;
        if (std::fclose(f) != 0 && ok) {
            ok = false;
            e = errno;
        }
        if (!ok)
            throw UserError(path + ": cannot write " + what + ": " +
                            (e ? errnoText(e) : "short write"));
    });
}

void checkWritable(const std::string& path, const std::string& what) {
    if (path.empty()) throw UserError("empty path for a " + what);
    if (fs::is_directory(path)) throw UserError(path + ": is a directory, not a " + what);
    if (isSpecialFile(path)) return;
    makeParent(path, what);
    fs::path parent = fs::path(path).parent_path();
    std::string dir = parent.empty() ? "." : parent.string();
    if (::access(dir.c_str(), W_OK) != 0)
        throw UserError(path + ": cannot write a " + what + " in '" + dir +
                        "': " + errnoText(errno));
}

}  // namespace loom
