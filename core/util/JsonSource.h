#pragma once
// A parsed JSON document that remembers where each value came from, so that semantic
// errors ("unknown parameter") can name file:line:column like syntax errors do.
#include <map>
#include <nlohmann/json.hpp>
#include <string>

namespace loom {

using json = nlohmann::json;

struct SourceLocation {
    int line = 0;    // 1-based; 0 = unknown
    int column = 0;  // 1-based
};

// Deepest nesting of arrays and objects any Loom JSON file may have. Graphs and scenes need
// fewer than 10 levels; the limit keeps recursive code (and the parser's callers) off the end
// of the stack.
constexpr int kMaxJsonDepth = 256;

// Throws UserError "file:line:col: JSON nested deeper than 256 levels" when `text` nests
// deeper than kMaxJsonDepth. Strings are skipped; the text need not be valid JSON.
void checkJsonDepth(const std::string& text, const std::string& filename);

class JsonSource {
public:
    // Throws UserError "file:line:col: JSON syntax error: ..." on malformed text.
    static JsonSource parse(const std::string& text, const std::string& filename);
    static JsonSource load(const std::string& path);

    const json& root() const { return mRoot; }
    const std::string& filename() const { return mFilename; }
    // Location of the value at a JSON pointer ("/passes/2/params/exposure"); for object members
    // this is the position of the key. Falls back to the nearest known parent.
    SourceLocation locate(const std::string& pointer) const;
    // "file:line:col" (or "file" when unknown) for error messages.
    std::string where(const std::string& pointer) const;

private:
    json mRoot;
    std::string mFilename;
    std::map<std::string, SourceLocation> mLocations;
};

}  // namespace loom
