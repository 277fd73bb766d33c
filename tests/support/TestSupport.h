#pragma once
// Helpers shared by the test executables: temporary directories, file writing and the
// "file:line:col" of a piece of JSON text (so tests can assert where an error points).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace loom::test {

namespace fs = std::filesystem;

// A fresh directory under the system temp dir, removed when the object dies.
class TempDir {
public:
    explicit TempDir(const std::string& tag = "loom-test") {
        std::string pattern = (fs::temp_directory_path() / (tag + "-XXXXXX")).string();
        if (!::mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
        mPath = pattern;
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(mPath, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const fs::path& path() const { return mPath; }
    std::string str() const { return mPath.string(); }
    std::string operator/(const std::string& rel) const { return (mPath / rel).string(); }

private:
    fs::path mPath;
};

inline void writeFile(const std::string& path, const std::string& text) {
    fs::create_directories(fs::path(path).parent_path());
    std::ofstream out(path, std::ios::binary);
    ASSERT_TRUE(out) << "cannot write " << path;
    out << text;
}

inline std::string readFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// "file:line:col" (1-based) of the n-th occurrence of `needle` in `text`.
inline std::string locationOf(const std::string& file, const std::string& text,
                              const std::string& needle, int occurrence = 0) {
    size_t pos = text.find(needle);
    for (int i = 0; i < occurrence && pos != std::string::npos; ++i)
        pos = text.find(needle, pos + 1);
    if (pos == std::string::npos) {
        ADD_FAILURE() << "'" << needle << "' not in test text";
        return "?";
    }
    int line = 1, col = 1;
    for (size_t i = 0; i < pos; ++i) {
        if (text[i] == '\n') {
            ++line;
            col = 1;
        } else {
            ++col;
        }
    }
    return file + ":" + std::to_string(line) + ":" + std::to_string(col);
}

}  // namespace loom::test
