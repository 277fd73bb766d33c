#include "core/util/JsonSource.h"

#include <cstring>
#include <fstream>
#include <sstream>

#include "core/util/Error.h"

namespace loom {

namespace {

// Minimal scanner over already-validated JSON that records the position of every value.
class LocationScanner {
public:
    LocationScanner(const std::string& text, std::map<std::string, SourceLocation>& out)
        : mText(text), mOut(out) {}
    void run() {
        skipWs();
        value("");
    }

private:
    const std::string& mText;
    std::map<std::string, SourceLocation>& mOut;
    size_t mPos = 0;
    int mLine = 1, mCol = 1;

    void advance() {
        if (mText[mPos] == '\n') {
            ++mLine;
            mCol = 1;
        } else {
            ++mCol;
        }
        ++mPos;
    }
    void skipWs() {
        while (mPos < mText.size() && std::isspace(static_cast<unsigned char>(mText[mPos])))
            advance();
    }
    std::string string() {
        std::string s;
        advance();  // opening quote
        while (mPos < mText.size() && mText[mPos] != '"') {
            if (mText[mPos] == '\\') {
                advance();
                if (mPos < mText.size()) s += mText[mPos];
            } else {
                s += mText[mPos];
            }
            advance();
        }
        if (mPos < mText.size()) advance();
        return s;
    }
    static std::string escapePointer(const std::string& key) {
        std::string r;
        for (char c : key) {
            if (c == '~')
                r += "~0";
            else if (c == '/')
                r += "~1";
            else
                r += c;
        }
        return r;
    }
    void value(const std::string& ptr) {
        if (mPos >= mText.size()) return;
        if (!mOut.count(ptr)) mOut[ptr] = {mLine, mCol};
        char c = mText[mPos];
        if (c == '{') {
            advance();
            skipWs();
            while (mPos < mText.size() && mText[mPos] != '}') {
                SourceLocation keyLoc{mLine, mCol};
                std::string key = string();
                std::string child = ptr + "/" + escapePointer(key);
                mOut[child] = keyLoc;
                skipWs();
                if (mPos < mText.size() && mText[mPos] == ':') advance();
                skipWs();
                value(child);
                skipWs();
                if (mPos < mText.size() && mText[mPos] == ',') advance();
                skipWs();
            }
            if (mPos < mText.size()) advance();
        } else if (c == '[') {
            advance();
            skipWs();
            int index = 0;
            while (mPos < mText.size() && mText[mPos] != ']') {
                value(ptr + "/" + std::to_string(index++));
                skipWs();
                if (mPos < mText.size() && mText[mPos] == ',') advance();
                skipWs();
            }
            if (mPos < mText.size()) advance();
        } else if (c == '"') {
            string();
        } else {
            while (mPos < mText.size() && !std::strchr(",]}", mText[mPos]) &&
                   !std::isspace(static_cast<unsigned char>(mText[mPos])))
                advance();
        }
    }
};

SourceLocation offsetToLocation(const std::string& text, size_t offset) {
    SourceLocation loc{1, 1};
    for (size_t i = 0; i < offset && i < text.size(); ++i) {
        if (text[i] == '\n') {
            ++loc.line;
            loc.column = 1;
        } else {
            ++loc.column;
        }
    }
    return loc;
}

}  // namespace

void checkJsonDepth(const std::string& text, const std::string& filename) {
    int depth = 0;
    bool inString = false;
    for (size_t i = 0; i < text.size(); ++i) {
        char c = text[i];
        if (inString) {
            if (c == '\\')
                ++i;
            else if (c == '"')
                inString = false;
        } else if (c == '"') {
            inString = true;
        } else if (c == '[' || c == '{') {
            if (++depth > kMaxJsonDepth) {
                SourceLocation loc = offsetToLocation(text, i);
                throw UserError(filename + ":" + std::to_string(loc.line) + ":" +
                                std::to_string(loc.column) + ": JSON nested deeper than " +
                                std::to_string(kMaxJsonDepth) + " levels");
            }
        } else if (c == ']' || c == '}') {
            --depth;
        }
    }
}

JsonSource JsonSource::parse(const std::string& text, const std::string& filename) {
    JsonSource src;
    src.mFilename = filename;
    checkJsonDepth(text, filename);
    try {
        src.mRoot = json::parse(text);
    } catch (const json::out_of_range& e) {
        // A number too large for a double (1e400): name it and where it is.
        std::string msg = e.what();
        std::string token;
        if (auto q = msg.find('\''); q != std::string::npos)
            token = msg.substr(q + 1, msg.rfind('\'') - q - 1);
        size_t at = token.empty() ? std::string::npos : text.find(token);
        SourceLocation loc = offsetToLocation(text, at == std::string::npos ? 0 : at);
        throw UserError(filename + ":" + std::to_string(loc.line) + ":" +
                        std::to_string(loc.column) +
                        ": JSON number out of range: " + (token.empty() ? msg : token));
    } catch (const json::parse_error& e) {
        // byte is 1-based and points one past the offending character.
        SourceLocation loc = offsetToLocation(text, e.byte > 0 ? e.byte - 1 : 0);
        std::string msg = e.what();
        auto pos = msg.find("syntax error");
        if (pos != std::string::npos) msg = msg.substr(pos);
        throw UserError(filename + ":" + std::to_string(loc.line) + ":" +
                        std::to_string(loc.column) + ": JSON " + msg);
    }
    LocationScanner(text, src.mLocations).run();
    return src;
}

JsonSource JsonSource::load(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw UserError(path + ": cannot open file");
    std::stringstream ss;
    ss << in.rdbuf();
    return parse(ss.str(), path);
}

SourceLocation JsonSource::locate(const std::string& pointer) const {
    std::string p = pointer;
    while (true) {
        auto it = mLocations.find(p);
        if (it != mLocations.end()) return it->second;
        auto slash = p.rfind('/');
        if (slash == std::string::npos || p.empty()) return {};
        p = p.substr(0, slash);
    }
}

std::string JsonSource::where(const std::string& pointer) const {
    SourceLocation loc = locate(pointer);
    if (loc.line == 0) return mFilename;
    return mFilename + ":" + std::to_string(loc.line) + ":" + std::to_string(loc.column);
}

}  // namespace loom
