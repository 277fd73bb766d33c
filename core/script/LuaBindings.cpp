// The `loom` Lua module. Conventions for every C function here:
//  - its body is C++ and runs through guarded<>(): exceptions become Lua errors only after the
//    C++ scope is left (no longjmp through C++ frames);
//  - argument checks throw ScriptError (never luaL_check*, which would longjmp);
//  - tables are read with raw accessors (no metamethods, so no Lua errors mid-function).
// Lua API reference: scripts/README.md.
#include "core/script/LuaBindings.h"

#include <unistd.h>
#include <lua.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "core/graph/Renderer.h"
#include "core/image/Flip.h"
#include "core/image/Image.h"
#include "core/scene/Camera.h"
#include "core/scene/SceneGpu.h"
#include "core/script/Csv.h"
#include "core/script/Plot.h"
#include "core/util/AtomicFile.h"
#include "core/util/Error.h"
#include "core/util/JsonSource.h"
#include "core/util/Log.h"

#ifndef LOOM_SOURCE_DIR
#define LOOM_SOURCE_DIR ""
#endif

namespace loom::script {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

class ScriptError : public UserError {
public:
    using UserError::UserError;
};

constexpr const char* kRendererMeta = "loom.Renderer";
constexpr const char* kImageMeta = "loom.Image";
constexpr const char* kHostKey = "loom.host";

// Per-runtime state reachable from every C function through the registry.
struct Host {
    LuaRuntime::Options options;
    std::string scriptDir;
    std::map<std::string, std::string> named;  // NAME=VALUE / --NAME VALUE script arguments
    std::map<std::string, std::shared_ptr<gpu::Context>> contexts;  // by requested device
    std::set<std::string> sweepCsvs;  // loom.write_csv targets of a sharded run (the manifest)
    Clock::time_point start = Clock::now();
    struct Progress {
        bool active = false;
        std::string label;
        double last = -1;
        Clock::time_point start, lastPrint;
    } progress;
};

Host& host(lua_State* L) {
    lua_getfield(L, LUA_REGISTRYINDEX, kHostKey);
    auto* h = static_cast<Host*>(lua_touserdata(L, -1));
    lua_pop(L, 1);
    return *h;
}

// ---------------------------------------------------------------------------------------------
// The C boundary. The message lives in a fixed buffer so that nothing with a destructor is
// alive when lua_error() longjmps out of guarded().

thread_local char tError[16384];

void storeError(const char* prefix, const char* what) {
    std::snprintf(tError, sizeof(tError), "%s%s", prefix, what);
}

template <int (*F)(lua_State*)>
int guarded(lua_State* L) {
    int results = -1;
    {
        try {
            results = F(L);
        } catch (const UserError& e) {
            storeError("", e.what());
        } catch (const std::exception& e) {
            storeError("internal error: ", e.what());
        } catch (...) {
            storeError("internal error: ", "unknown C++ exception");
        }
    }
    if (results >= 0) return results;
    luaL_where(L, 1);  // "script.lua:LINE: " of the Lua code that called us
    lua_pushstring(L, tError);
    lua_concat(L, 2);
    return lua_error(L);
}

// ---------------------------------------------------------------------------------------------
// Argument helpers (throwing).

std::string describe(lua_State* L, int i) {
    switch (lua_type(L, i)) {
        case LUA_TNUMBER:
            return lua_isinteger(L, i) ? fmt::format("number {}", lua_tointeger(L, i))
                                       : fmt::format("number {}", lua_tonumber(L, i));
        case LUA_TSTRING:
            return fmt::format("string \"{}\"", lua_tostring(L, i));
        default:
            return luaL_typename(L, i);
    }
}

std::string argString(lua_State* L, int i, const std::string& fn, const std::string& what) {
    if (lua_type(L, i) != LUA_TSTRING)
        throw ScriptError(fmt::format("{}: {} must be a string, got {}", fn, what, describe(L, i)));
    size_t n = 0;
    const char* s = lua_tolstring(L, i, &n);
    return std::string(s, n);
}

double argNumber(lua_State* L, int i, const std::string& fn, const std::string& what) {
    if (lua_type(L, i) != LUA_TNUMBER)
        throw ScriptError(fmt::format("{}: {} must be a number, got {}", fn, what, describe(L, i)));
    return lua_tonumber(L, i);
}

int64_t argInteger(lua_State* L, int i, const std::string& fn, const std::string& what,
                   int64_t lo = INT64_MIN, int64_t hi = INT64_MAX) {
    int isInt = 0;
    lua_Integer v = lua_type(L, i) == LUA_TNUMBER ? lua_tointegerx(L, i, &isInt) : 0;
    if (!isInt)
        throw ScriptError(
            fmt::format("{}: {} must be an integer, got {}", fn, what, describe(L, i)));
    if (v < lo || v > hi)
        throw ScriptError(fmt::format("{}: {} must be in [{}, {}], got {}", fn, what, lo,
                                      hi == INT64_MAX ? std::string("inf") : std::to_string(hi),
                                      v));
    return v;
}

// Pushes t[key] without metamethods; returns its type. t must be an absolute index.
int rawField(lua_State* L, int t, const char* key) {
    lua_pushstring(L, key);
    return lua_rawget(L, t);
}

// Throws when the options table has a key outside `valid` (names them all).
void checkKeys(lua_State* L, int t, const std::string& fn,
               std::initializer_list<const char*> valid) {
    lua_pushnil(L);
    while (lua_next(L, t)) {
        lua_pop(L, 1);
        std::string list;
        for (auto* v : valid) list += (list.empty() ? "" : ", ") + std::string(v);
        if (lua_type(L, -1) != LUA_TSTRING)
            throw ScriptError(
                fmt::format("{}: options must be named (key = value); valid keys: {}", fn, list));
        std::string key = lua_tostring(L, -1);
        if (std::none_of(valid.begin(), valid.end(), [&](const char* v) { return key == v; }))
            throw ScriptError(fmt::format("{}: unknown key '{}'; valid keys: {}", fn, key, list));
    }
}

std::optional<std::string> optStringField(lua_State* L, int t, const char* key,
                                          const std::string& fn) {
    std::optional<std::string> out;
    if (rawField(L, t, key) != LUA_TNIL) out = argString(L, -1, fn, std::string("'") + key + "'");
    lua_pop(L, 1);
    return out;
}

std::optional<double> optNumberField(lua_State* L, int t, const char* key, const std::string& fn) {
    std::optional<double> out;
    if (rawField(L, t, key) != LUA_TNIL) out = argNumber(L, -1, fn, std::string("'") + key + "'");
    lua_pop(L, 1);
    return out;
}

std::optional<int64_t> optIntegerField(lua_State* L, int t, const char* key, const std::string& fn,
                                       int64_t lo, int64_t hi) {
    std::optional<int64_t> out;
    if (rawField(L, t, key) != LUA_TNIL)
        out = argInteger(L, -1, fn, std::string("'") + key + "'", lo, hi);
    lua_pop(L, 1);
    return out;
}

bool optBoolField(lua_State* L, int t, const char* key, const std::string& fn, bool def) {
    int type = rawField(L, t, key);
    bool out = def;
    if (type == LUA_TBOOLEAN)
        out = lua_toboolean(L, -1);
    else if (type != LUA_TNIL)
        throw ScriptError(
            fmt::format("{}: '{}' must be a boolean, got {}", fn, key, describe(L, -1)));
    lua_pop(L, 1);
    return out;
}

// An array table of numbers at index i.
std::vector<double> numberArray(lua_State* L, int i, const std::string& fn,
                                const std::string& what) {
    i = lua_absindex(L, i);
    if (lua_type(L, i) != LUA_TTABLE)
        throw ScriptError(
            fmt::format("{}: {} must be an array of numbers, got {}", fn, what, describe(L, i)));
    std::vector<double> out;
    lua_Integer n = lua_Integer(lua_rawlen(L, i));
    for (lua_Integer k = 1; k <= n; ++k) {
        lua_rawgeti(L, i, k);
        if (lua_type(L, -1) != LUA_TNUMBER)
            throw ScriptError(
                fmt::format("{}: {}[{}] must be a number, got {}", fn, what, k, describe(L, -1)));
        out.push_back(lua_tonumber(L, -1));
        lua_pop(L, 1);
    }
    return out;
}

// ---------------------------------------------------------------------------------------------
// Lua <-> JSON. Integers stay integers; arrays are tables with keys 1..n; other tables are
// objects with string keys; an empty table is an empty object.

// `ancestors` holds the tables being converted, outermost first: a table met again is a cycle.
json toJson(lua_State* L, int idx, const std::string& where, std::vector<const void*>& ancestors) {
    idx = lua_absindex(L, idx);
    switch (lua_type(L, idx)) {
        case LUA_TNIL:
            return nullptr;
        case LUA_TBOOLEAN:
            return bool(lua_toboolean(L, idx));
        case LUA_TNUMBER:
            if (lua_isinteger(L, idx)) return int64_t(lua_tointeger(L, idx));
            return double(lua_tonumber(L, idx));
        case LUA_TSTRING: {
            size_t n = 0;
            const char* s = lua_tolstring(L, idx, &n);
            return std::string(s, n);
        }
        case LUA_TTABLE: {
            const void* self = lua_topointer(L, idx);
            if (std::find(ancestors.begin(), ancestors.end(), self) != ancestors.end())
                throw ScriptError(where +
                                  ": the table contains itself (a cycle); JSON cannot "
                                  "hold it");
            if (ancestors.size() >= size_t(kMaxJsonDepth))
                throw ScriptError(
                    fmt::format("{}: tables nested deeper than {} levels", where, kMaxJsonDepth));
            // Each level holds a key and a value on the Lua stack.
            if (!lua_checkstack(L, 4)) throw ScriptError(where + ": Lua stack exhausted");
            ancestors.push_back(self);
            struct Pop {
                std::vector<const void*>& a;
                ~Pop() { a.pop_back(); }
            } pop{ancestors};
            size_t count = 0;
            bool allIntegerKeys = true;
            lua_Integer maxKey = 0;
            lua_pushnil(L);
            while (lua_next(L, idx)) {
                ++count;
                if (lua_type(L, -2) == LUA_TNUMBER && lua_isinteger(L, -2) &&
                    lua_tointeger(L, -2) >= 1)
                    maxKey = std::max(maxKey, lua_tointeger(L, -2));
                else
                    allIntegerKeys = false;
                lua_pop(L, 1);
            }
            if (count == 0) return json::object();
            if (allIntegerKeys) {
                if (size_t(maxKey) != count)
                    throw ScriptError(where + ": array table has holes (nil elements)");
                json arr = json::array();
                for (lua_Integer k = 1; k <= maxKey; ++k) {
                    lua_rawgeti(L, idx, k);
                    arr.push_back(toJson(L, -1, fmt::format("{}[{}]", where, k), ancestors));
                    lua_pop(L, 1);
                }
                return arr;
            }
            json obj = json::object();
            lua_pushnil(L);
            while (lua_next(L, idx)) {
                if (lua_type(L, -2) != LUA_TSTRING)
                    throw ScriptError(fmt::format(
                        "{}: the table mixes array elements and named keys (key {}); JSON needs "
                        "an array (keys 1..n) or an object (string keys)",
                        where, describe(L, -2)));
                std::string key = lua_tostring(L, -2);
                obj[key] = toJson(L, -1, where + "." + key, ancestors);
                lua_pop(L, 1);
            }
            return obj;
        }
        default:
            throw ScriptError(
                fmt::format("{}: a {} cannot be converted to JSON", where, luaL_typename(L, idx)));
    }
}

json toJson(lua_State* L, int idx, const std::string& where) {
    std::vector<const void*> ancestors;
    return toJson(L, idx, where, ancestors);
}

void pushJson(lua_State* L, const json& j) {
    // Arrays and objects hold the table and one value on the stack per level.
    if (!lua_checkstack(L, 3)) throw ScriptError("JSON too deeply nested for the Lua stack");
    switch (j.type()) {
        case json::value_t::boolean:
            lua_pushboolean(L, j.get<bool>());
            break;
        case json::value_t::number_integer:
            lua_pushinteger(L, j.get<int64_t>());
            break;
        case json::value_t::number_unsigned:
            lua_pushinteger(L, lua_Integer(j.get<uint64_t>()));
            break;
        case json::value_t::number_float:
            lua_pushnumber(L, j.get<double>());
            break;
        case json::value_t::string: {
            const auto& s = j.get_ref<const std::string&>();
            lua_pushlstring(L, s.data(), s.size());
            break;
        }
        case json::value_t::array: {
            lua_createtable(L, int(j.size()), 0);
            int k = 1;
            for (auto& v : j) {
                pushJson(L, v);
                lua_rawseti(L, -2, k++);
            }
            break;
        }
        case json::value_t::object: {
            lua_createtable(L, 0, int(j.size()));
            for (auto& [k, v] : j.items()) {
                pushJson(L, v);
                lua_setfield(L, -2, k.c_str());
            }
            break;
        }
        default:
            lua_pushnil(L);
            break;
    }
}

// ---------------------------------------------------------------------------------------------
// Files and devices

// Input files (graphs, scenes, camera paths, images): as given, else next to the script, else
// in the source tree (so `loom run scripts/x.lua` works from any directory).
std::string resolveInput(Host& h, const std::string& path, const std::string& fn,
                         const std::string& what) {
    if (path.empty()) throw ScriptError(fmt::format("{}: the {} path is empty", fn, what));
    if (fs::path(path).is_absolute() || fs::exists(path)) {
        if (!fs::exists(path))
            throw ScriptError(fmt::format("{}: {} not found: '{}'", fn, what, path));
        return path;
    }
    std::vector<std::string> tried = {"the working directory"};
    if (!h.scriptDir.empty()) {
        fs::path p = fs::path(h.scriptDir) / path;
        if (fs::exists(p)) return p.string();
        tried.push_back(h.scriptDir);
    }
    // Installed: PREFIX/share/loom (graphs/, scripts/, scenes/); in a build tree: the sources.
    std::string src = installedDataDir();
    if (src.empty()) src = LOOM_SOURCE_DIR;
    if (!src.empty()) {
        fs::path p = fs::path(src) / path;
        if (fs::exists(p)) return p.string();
        tried.push_back(src);
    }
    std::string list;
    for (auto& t : tried) list += (list.empty() ? "" : ", ") + t;
    throw ScriptError(fmt::format("{}: {} not found: '{}' (looked in {})", fn, what, path, list));
}

void makeParentDirs(const std::string& path) {
    auto parent = fs::path(path).parent_path();
    if (!parent.empty()) fs::create_directories(parent);
}

std::shared_ptr<gpu::Context> contextFor(Host& h, const std::string& device) {
    if (auto it = h.contexts.find(device); it != h.contexts.end()) return it->second;
    std::shared_ptr<gpu::Context> ctx;
    if (device.empty() && h.options.gpu) {
        ctx = h.options.gpu;
    } else {
        gpu::Context::Options o;
        o.device = device;
        o.cacheDir = h.options.cacheDir;
        ctx = gpu::Context::create(o);
    }
    // Another name for a device we already use ("" and "0", say): share that context.
    for (auto& [name, c] : h.contexts)
        if (c->deviceInfo().index == ctx->deviceInfo().index &&
            c->deviceInfo().name == ctx->deviceInfo().name) {
            ctx = c;
            break;
        }
    h.contexts[device] = ctx;
    return ctx;
}

// ---------------------------------------------------------------------------------------------
// Userdata

template <class T>
void pushOwned(lua_State* L, std::unique_ptr<T> obj, const char* meta) {
    auto** p = static_cast<T**>(lua_newuserdatauv(L, sizeof(T*), 0));
    *p = nullptr;
    luaL_setmetatable(L, meta);
    *p = obj.release();
}

template <class T>
int gcOwned(lua_State* L, const char* meta) {
    auto** p = static_cast<T**>(luaL_testudata(L, 1, meta));
    if (p && *p) {
        T* obj = *p;
        *p = nullptr;
        try {
            delete obj;
        } catch (...) {  // a destructor must not take the process down from a finalizer
        }
    }
    return 0;
}

Renderer& self(lua_State* L, const char* method) {
    auto** p = static_cast<Renderer**>(luaL_testudata(L, 1, kRendererMeta));
    if (!p)
        throw ScriptError(
            fmt::format("r:{}: expected a renderer as self, got {}; call it as "
                        "r:{}(...) with ':'",
                        method, describe(L, 1), method));
    if (!*p) throw ScriptError(fmt::format("r:{}: this renderer was closed", method));
    return **p;
}

ImageData& imageArg(lua_State* L, int i, const std::string& fn, const std::string& what) {
    auto** p = static_cast<ImageData**>(luaL_testudata(L, i, kImageMeta));
    if (!p || !*p)
        throw ScriptError(fmt::format("{}: {} must be an image, got {}", fn, what, describe(L, i)));
    return **p;
}

void pushImage(lua_State* L, ImageData img) {
    pushOwned(L, std::make_unique<ImageData>(std::move(img)), kImageMeta);
}

// ---------------------------------------------------------------------------------------------
// loom.renderer

int lRenderer(lua_State* L) {
    const std::string fn = "loom.renderer";
    if (lua_type(L, 1) != LUA_TTABLE)
        throw ScriptError(fn +
                          ": expects a table {graph=, scene=, width=, height=, seed=, "
                          "device=, params=}, got " +
                          describe(L, 1));
    checkKeys(L, 1, fn, {"graph", "scene", "width", "height", "seed", "device", "params"});
    Host& h = host(L);
    auto graph = optStringField(L, 1, "graph", fn);
    if (!graph) throw ScriptError(fn + ": 'graph' (a render graph JSON file) is required");
    auto scene = optStringField(L, 1, "scene", fn);
    uint32_t width = uint32_t(optIntegerField(L, 1, "width", fn, 1, 16384).value_or(256));
    uint32_t height = uint32_t(optIntegerField(L, 1, "height", fn, 1, 16384).value_or(256));
    uint32_t seed = uint32_t(optIntegerField(L, 1, "seed", fn, 0, 0xffffffffll).value_or(0));
    std::string device = optStringField(L, 1, "device", fn).value_or("");

    auto g = RenderGraph::load(resolveInput(h, *graph, fn, "graph file"));
    std::string scenePath = scene ? resolveInput(h, *scene, fn, "scene file") : "";
    auto r = std::make_unique<Renderer>(contextFor(h, device), std::move(g), width, height, seed,
                                        h.options.cacheDir);
    if (scene) r->loadScene(scenePath);
    if (rawField(L, 1, "params") != LUA_TNIL) {
        int t = lua_gettop(L);
        if (lua_type(L, t) != LUA_TTABLE)
            throw ScriptError(fn + ": 'params' must be a table {[\"pass.param\"] = value}");
        lua_pushnil(L);
        while (lua_next(L, t)) {
            std::string key = argString(L, -2, fn, "a 'params' key");
            r->graph().setParam(key, toJson(L, -1, fn + " params['" + key + "']"));
            lua_pop(L, 1);
        }
    }
    lua_pop(L, 1);
    pushOwned(L, std::move(r), kRendererMeta);
    return 1;
}

// ---------------------------------------------------------------------------------------------
// Renderer methods: frames

int rFrame(lua_State* L) {
    self(L, "frame").frame();
    return 0;
}

int rFrames(lua_State* L) {
    Renderer& r = self(L, "frames");
    auto n = argInteger(L, 2, "r:frames", "the frame count", 0, 1 << 30);
    r.frames(uint32_t(n));
    return 0;
}

// Frames until the summed GPU frame times reach the budget: the last frame crosses it, so the
// overshoot is less than one frame. Returns frames rendered and the GPU milliseconds spent.
int rRunForMs(lua_State* L) {
    Renderer& r = self(L, "run_for_ms");
    double budget = argNumber(L, 2, "r:run_for_ms", "the time budget (ms)");
    if (!std::isfinite(budget) || budget < 0)
        throw ScriptError(
            fmt::format("r:run_for_ms: the time budget must be a finite number "
                        ">= 0 (ms), got {}",
                        budget));
    double spent = 0.0;
    int64_t frames = 0;
    while (spent < budget) {
        auto t0 = Clock::now();
        r.frame();
        double ms = r.graph().frameGpuMs();
        // Devices without timestamps report 0: fall back to wall time so the loop ends.
        if (!(ms > 0.0)) ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        spent += ms;
        ++frames;
    }
    lua_pushinteger(L, frames);
    lua_pushnumber(L, spent);
    return 2;
}

int rReset(lua_State* L) {
    self(L, "reset").reset();
    return 0;
}

int rClose(lua_State* L) {
    return gcOwned<Renderer>(L, kRendererMeta);
}

int rToString(lua_State* L) {
    auto** p = static_cast<Renderer**>(luaL_testudata(L, 1, kRendererMeta));
    std::string s = !p || !*p
                        ? "loom.Renderer (closed)"
                        : fmt::format("loom.Renderer '{}' {}x{}, {} frames", (*p)->graph().name(),
                                      (*p)->width(), (*p)->height(), (*p)->framesRendered());
    lua_pushstring(L, s.c_str());
    return 1;
}

int rWidth(lua_State* L) {
    lua_pushinteger(L, self(L, "width").width());
    return 1;
}

int rHeight(lua_State* L) {
    lua_pushinteger(L, self(L, "height").height());
    return 1;
}

int rFrameCount(lua_State* L) {
    lua_pushinteger(L, lua_Integer(self(L, "frame_count").framesRendered()));
    return 1;
}

int rResize(lua_State* L) {
    Renderer& r = self(L, "resize");
    auto w = argInteger(L, 2, "r:resize", "the width", 1, 16384);
    auto hgt = argInteger(L, 3, "r:resize", "the height", 1, 16384);
    r.resize(uint32_t(w), uint32_t(hgt));
    return 0;
}

int rSetSeed(lua_State* L) {
    Renderer& r = self(L, "set_seed");
    r.setSeed(uint32_t(argInteger(L, 2, "r:set_seed", "the seed", 0, 0xffffffffll)));
    r.reset();
    return 0;
}

// ---------------------------------------------------------------------------------------------
// Parameters

std::string joinNames(const std::vector<std::string>& names) {
    std::string s;
    for (auto& n : names) s += (s.empty() ? "" : ", ") + n;
    return s.empty() ? "(none)" : s;
}

// Finds pass and parameter with messages that list the valid names.
Pass& findParamPass(Renderer& r, const std::string& fn, const std::string& key) {
    auto dot = key.find('.');
    if (dot == std::string::npos || dot == 0 || dot + 1 == key.size())
        throw ScriptError(fmt::format("{}: expected 'pass.param', got '{}'", fn, key));
    std::string node = key.substr(0, dot), param = key.substr(dot + 1);
    Pass* p = r.graph().findPass(node);
    if (!p) {
        std::vector<std::string> names;
        for (auto& x : r.graph().passes()) names.push_back(x->name());
        throw ScriptError(fmt::format("{}: no pass named '{}' in graph '{}'; passes: {}", fn, node,
                                      r.graph().name(), joinNames(names)));
    }
    PassReflection refl = p->reflection();
    if (!refl.findParam(param)) {
        std::vector<std::string> names;
        for (auto& d : refl.params()) names.push_back(d.name);
        throw ScriptError(fmt::format("{}: {} '{}' has no parameter '{}'; valid parameters: {}", fn,
                                      p->type(), p->name(), param, joinNames(names)));
    }
    return *p;
}

int rSet(lua_State* L) {
    Renderer& r = self(L, "set");
    std::string key = argString(L, 2, "r:set", "the parameter name ('pass.param')");
    std::string fn = "r:set('" + key + "')";
    if (lua_isnone(L, 3)) throw ScriptError(fn + ": missing the value");
    findParamPass(r, fn, key);
    json value = toJson(L, 3, fn);
    try {
        r.graph().setParam(key, value);
    } catch (const UserError& e) {
        throw ScriptError(fn + ": " + e.what());
    }
    return 0;
}

int rGet(lua_State* L) {
    Renderer& r = self(L, "get");
    std::string key = argString(L, 2, "r:get", "the parameter name ('pass.param')");
    findParamPass(r, "r:get('" + key + "')", key);
    pushJson(L, r.graph().getParam(key));
    return 1;
}

int rParams(lua_State* L) {
    Renderer& r = self(L, "params");
    lua_newtable(L);
    for (auto& p : r.graph().passes()) {
        PassReflection refl = p->reflection();
        for (auto& d : refl.params()) {
            lua_createtable(L, 0, 7);
            pushJson(L, p->getParam(d.name));
            lua_setfield(L, -2, "value");
            lua_pushstring(L, paramTypeName(d.type));
            lua_setfield(L, -2, "type");
            pushJson(L, d.defaultValue);
            lua_setfield(L, -2, "default");
            if (d.min) {
                lua_pushnumber(L, *d.min);
                lua_setfield(L, -2, "min");
            }
            if (d.max) {
                lua_pushnumber(L, *d.max);
                lua_setfield(L, -2, "max");
            }
            lua_pushstring(L, d.doc.c_str());
            lua_setfield(L, -2, "doc");
            if (!d.choices.empty()) {
                pushJson(L, json(d.choices));
                lua_setfield(L, -2, "choices");
            }
            lua_setfield(L, -2, (p->name() + "." + d.name).c_str());
        }
    }
    return 1;
}

// ---------------------------------------------------------------------------------------------
// Graph editing

int rAddPass(lua_State* L) {
    Renderer& r = self(L, "add_pass");
    std::string type = argString(L, 2, "r:add_pass", "the pass type");
    std::string name = argString(L, 3, "r:add_pass", "the pass name");
    json params = json::object();
    if (!lua_isnoneornil(L, 4)) {
        if (lua_type(L, 4) != LUA_TTABLE)
            throw ScriptError("r:add_pass: the parameters must be a table, got " + describe(L, 4));
        params = toJson(L, 4, "r:add_pass params");
    }
    r.graph().addPass(type, name, params);
    return 0;
}

int rRemovePass(lua_State* L) {
    Renderer& r = self(L, "remove_pass");
    r.graph().removePass(argString(L, 2, "r:remove_pass", "the pass name"));
    return 0;
}

int rConnect(lua_State* L) {
    Renderer& r = self(L, "connect");
    r.graph().connect(argString(L, 2, "r:connect", "the source ('pass.port')"),
                      argString(L, 3, "r:connect", "the destination ('pass.port')"));
    return 0;
}

int rDisconnect(lua_State* L) {
    Renderer& r = self(L, "disconnect");
    r.graph().disconnect(argString(L, 2, "r:disconnect", "the source ('pass.port')"),
                         argString(L, 3, "r:disconnect", "the destination ('pass.port')"));
    return 0;
}

int rMarkOutput(lua_State* L) {
    Renderer& r = self(L, "mark_output");
    r.graph().markOutput(argString(L, 2, "r:mark_output", "the port ('pass.port')"));
    return 0;
}

int rUnmarkOutput(lua_State* L) {
    Renderer& r = self(L, "unmark_output");
    r.graph().unmarkOutput(argString(L, 2, "r:unmark_output", "the port ('pass.port')"));
    return 0;
}

int rSaveGraph(lua_State* L) {
    Renderer& r = self(L, "save_graph");
    std::string path = argString(L, 2, "r:save_graph", "the path");
    makeParentDirs(path);
    r.graph().save(path);
    return 0;
}

int rPasses(lua_State* L) {
    Renderer& r = self(L, "passes");
    lua_newtable(L);
    int k = 1;
    for (auto& p : r.graph().passes()) {
        lua_createtable(L, 0, 2);
        lua_pushstring(L, p->name().c_str());
        lua_setfield(L, -2, "name");
        lua_pushstring(L, p->type().c_str());
        lua_setfield(L, -2, "type");
        lua_rawseti(L, -2, k++);
    }
    return 1;
}

int rOutputs(lua_State* L) {
    Renderer& r = self(L, "outputs");
    pushJson(L, json(r.graph().outputs()));
    return 1;
}

// ---------------------------------------------------------------------------------------------
// Camera and animation

scene::SceneGpu& sceneOf(Renderer& r, const std::string& fn) {
    if (!r.scene())
        throw ScriptError(fn +
                          ": this renderer has no scene (create it with "
                          "loom.renderer{..., scene = \"file.json\"})");
    return *r.scene();
}

glm::vec3 vec3Field(lua_State* L, int t, const char* key, const std::string& fn, glm::vec3 def,
                    bool* given = nullptr) {
    int type = rawField(L, t, key);
    if (given) *given = type != LUA_TNIL;
    if (type == LUA_TNIL) {
        lua_pop(L, 1);
        return def;
    }
    std::vector<double> v = numberArray(L, -1, fn, std::string("'") + key + "'");
    if (v.size() != 3)
        throw ScriptError(
            fmt::format("{}: '{}' must be an array of 3 numbers, got {}", fn, key, v.size()));
    lua_pop(L, 1);
    return glm::vec3(float(v[0]), float(v[1]), float(v[2]));
}

// The vertical field of view of a camera at the given frame size (degrees).
float verticalFov(const scene::Camera& c, uint32_t width, uint32_t height) {
    using Axis = scene::Camera::FovAxis;
    bool xAxis = c.fovAxis == Axis::X || (c.fovAxis == Axis::Smaller && width <= height) ||
                 (c.fovAxis == Axis::Larger && width >= height);
    if (!xAxis) return c.fov;
    float aspect = float(width) / float(height);
    return glm::degrees(2.0f * std::atan(std::tan(glm::radians(c.fov) * 0.5f) / aspect));
}

struct Pose {
    glm::vec3 origin, target, up;
    float fovY;
};

Pose currentPose(Renderer& r, const scene::SceneGpu& s) {
    scene::Camera c = scene::cameraAt(s.cpu().camera, r.time());
    Pose p;
    p.origin = glm::vec3(c.toWorld * glm::vec4(0, 0, 0, 1));
    glm::vec3 dir = glm::normalize(glm::vec3(c.toWorld * glm::vec4(0, 0, 1, 0)));
    p.up = glm::normalize(glm::vec3(c.toWorld * glm::vec4(0, 1, 0, 0)));
    // Keep the look-at distance meaningful: aim at the scene centre's depth along the view.
    glm::vec4 sphere = s.boundingSphere();
    float dist = glm::dot(glm::vec3(sphere) - p.origin, dir);
    p.target = p.origin + dir * (dist > 1e-3f ? dist : 1.0f);
    p.fovY = verticalFov(c, r.width(), r.height());
    return p;
}

void pushVec3(lua_State* L, glm::vec3 v) {
    lua_createtable(L, 3, 0);
    for (int i = 0; i < 3; ++i) {
        lua_pushnumber(L, v[i]);
        lua_rawseti(L, -2, i + 1);
    }
}

// r:camera() returns {origin, target, up, fov}; r:camera{...} replaces the camera (and its path)
// with the given fields, the others kept from the current pose.
int rCamera(lua_State* L) {
    Renderer& r = self(L, "camera");
    const std::string fn = "r:camera";
    auto& s = sceneOf(r, fn);
    Pose pose = currentPose(r, s);
    if (lua_isnoneornil(L, 2)) {
        lua_createtable(L, 0, 4);
        pushVec3(L, pose.origin);
        lua_setfield(L, -2, "origin");
        pushVec3(L, pose.target);
        lua_setfield(L, -2, "target");
        pushVec3(L, pose.up);
        lua_setfield(L, -2, "up");
        lua_pushnumber(L, pose.fovY);
        lua_setfield(L, -2, "fov");
        return 1;
    }
    if (lua_type(L, 2) != LUA_TTABLE)
        throw ScriptError(fn + ": expects a table {origin=, target=, up=, fov=}, got " +
                          describe(L, 2));
    checkKeys(L, 2, fn, {"origin", "target", "up", "fov"});
    glm::vec3 origin = vec3Field(L, 2, "origin", fn, pose.origin);
    glm::vec3 target = vec3Field(L, 2, "target", fn, pose.target);
    glm::vec3 up = vec3Field(L, 2, "up", fn, pose.up);
    float fov = float(optNumberField(L, 2, "fov", fn).value_or(pose.fovY));
    if (!(fov > 0.0f && fov < 180.0f))
        throw ScriptError(fmt::format("{}: 'fov' must be in (0, 180) degrees, got {}", fn, fov));
    if (glm::length(target - origin) < 1e-6f)
        throw ScriptError(fn + ": 'origin' and 'target' coincide");
    scene::Camera c = s.cpu().camera;
    c.toWorld = scene::lookAtMatrix(origin, target, up);
    c.fov = fov;
    c.fovAxis = scene::Camera::FovAxis::Y;
    c.path.clear();
    s.setCamera(c);
    return 0;
}

// Keyframes: [{"time": 0, "origin": [...], "target": [...], "up": [...], "fov": 45}, ...] or
// {"path": [...]}; missing fields repeat the previous keyframe (the first: the current camera).
int rCameraPath(lua_State* L) {
    Renderer& r = self(L, "camera_path");
    const std::string fn = "r:camera_path";
    auto& s = sceneOf(r, fn);
    std::string file =
        resolveInput(host(L), argString(L, 2, fn, "the keyframe file"), fn, "camera path file");
    JsonSource src = JsonSource::load(file);
    const json* keys = &src.root();
    std::string base;
    if (keys->is_object() && keys->contains("path")) {
        keys = &(*keys)["path"];
        base = "/path";
    }
    if (!keys->is_array() || keys->empty())
        throw ScriptError(src.where(base) +
                          ": expected a non-empty array of keyframes {\"time\", \"origin\", "
                          "\"target\", \"up\", \"fov\"}");
    Pose pose = currentPose(r, s);
    std::vector<scene::CameraKeyframe> path;
    for (size_t i = 0; i < keys->size(); ++i) {
        const json& k = (*keys)[i];
        std::string ptr = fmt::format("{}/{}", base, i);
        if (!k.is_object()) throw ScriptError(src.where(ptr) + ": a keyframe must be an object");
        for (auto& [key, v] : k.items())
            if (key != "time" && key != "origin" && key != "target" && key != "up" && key != "fov")
                throw ScriptError(src.where(ptr + "/" + key) + ": unknown key '" + key +
                                  "' in keyframe; valid keys: time, origin, target, up, fov");
        auto vec = [&](const char* key, glm::vec3 def) {
            if (!k.contains(key)) return def;
            const json& v = k[key];
            if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() ||
                !v[2].is_number())
                throw ScriptError(src.where(ptr + "/" + key) + ": '" + key +
                                  "' must be an array of 3 numbers");
            return glm::vec3(v[0].get<float>(), v[1].get<float>(), v[2].get<float>());
        };
        if (!k.contains("time") || !k["time"].is_number())
            throw ScriptError(src.where(ptr) + ": keyframe needs a numeric 'time' (frames)");
        scene::CameraKeyframe kf;
        kf.time = k["time"].get<float>();
        const scene::CameraKeyframe* prev = path.empty() ? nullptr : &path.back();
        kf.origin = vec("origin", prev ? prev->origin : pose.origin);
        kf.target = vec("target", prev ? prev->target : pose.target);
        kf.up = vec("up", prev ? prev->up : pose.up);
        kf.fovY = prev ? prev->fovY : pose.fovY;
        if (k.contains("fov")) {
            if (!k["fov"].is_number() || !(k["fov"].get<double>() > 0) ||
                !(k["fov"].get<double>() < 180))
                throw ScriptError(src.where(ptr + "/fov") + ": 'fov' must be in (0, 180) degrees");
            kf.fovY = k["fov"].get<float>();
        }
        if (prev && !(kf.time > prev->time))
            throw ScriptError(src.where(ptr + "/time") + ": keyframe times must increase");
        if (glm::length(kf.target - kf.origin) < 1e-6f)
            throw ScriptError(src.where(ptr) + ": keyframe origin and target coincide");
        path.push_back(kf);
    }
    scene::Camera c = s.cpu().camera;
    c.path = path;
    c.toWorld = scene::lookAtMatrix(path[0].origin, path[0].target, path[0].up);
    c.fov = path[0].fovY;
    c.fovAxis = scene::Camera::FovAxis::Y;
    s.setCamera(c);
    lua_pushinteger(L, lua_Integer(path.size()));
    lua_pushnumber(L, path.back().time);
    return 2;
}

int rSetTime(lua_State* L) {
    Renderer& r = self(L, "set_time");
    double t = argNumber(L, 2, "r:set_time", "the time (frames)");
    if (!std::isfinite(t)) throw ScriptError("r:set_time: the time must be finite");
    r.setTime(float(t));
    return 0;
}

// r:shutter() returns the camera's shutter interval (open, close) in frames after the frame
// time; r:shutter(open, close) sets it (equal: no motion blur). Keeps the camera path.
int rShutter(lua_State* L) {
    Renderer& r = self(L, "shutter");
    const std::string fn = "r:shutter";
    auto& s = sceneOf(r, fn);
    scene::Camera c = s.cpu().camera;
    if (lua_isnoneornil(L, 2)) {
        lua_pushnumber(L, c.shutterOpen);
        lua_pushnumber(L, c.shutterClose);
        return 2;
    }
    double open = argNumber(L, 2, fn, "the shutter open time (frames)");
    double close = argNumber(L, 3, fn, "the shutter close time (frames)");
    if (!std::isfinite(open) || !std::isfinite(close) || close < open)
        throw ScriptError(fmt::format(
            "{}: the shutter must be finite with open <= close, got ({}, {})", fn, open, close));
    c.shutterOpen = float(open);
    c.shutterClose = float(close);
    s.setCamera(c);
    return 0;
}

int rTime(lua_State* L) {
    lua_pushnumber(L, self(L, "time").time());
    return 1;
}

// ---------------------------------------------------------------------------------------------
// Images, timings, statistics

ImageData readPort(Renderer& r, const std::string& fn, const std::string& port) {
    const auto& outs = r.graph().outputs();
    if (std::find(outs.begin(), outs.end(), port) == outs.end())
        throw ScriptError(fmt::format(
            "{}: '{}' is not a marked output of graph '{}'; marked outputs: {} (mark it first "
            "with r:mark_output(\"{}\"))",
            fn, port, r.graph().name(), joinNames(outs), port));
    return r.readOutput(port);
}

int rImage(lua_State* L) {
    Renderer& r = self(L, "image");
    std::string port = argString(L, 2, "r:image", "the port ('pass.port')");
    pushImage(L, readPort(r, "r:image", port));
    return 1;
}

int rCapture(lua_State* L) {
    Renderer& r = self(L, "capture");
    std::string port = argString(L, 2, "r:capture", "the port ('pass.port')");
    std::string path = argString(L, 3, "r:capture", "the file path");
    writeImage(path, readPort(r, "r:capture", port));
    return 0;
}

int rTimings(lua_State* L) {
    Renderer& r = self(L, "timings");
    lua_createtable(L, 0, 2);
    lua_newtable(L);
    int k = 1;
    for (auto& t : r.graph().timings()) {
        lua_createtable(L, 0, 2);
        lua_pushstring(L, t.pass.c_str());
        lua_setfield(L, -2, "pass");
        lua_pushnumber(L, t.gpuMs);
        lua_setfield(L, -2, "ms");
        lua_rawseti(L, -2, k++);
    }
    lua_setfield(L, -2, "passes");
    lua_pushnumber(L, r.graph().frameGpuMs());
    lua_setfield(L, -2, "frame_ms");
    return 1;
}

int rStats(lua_State* L) {
    Renderer& r = self(L, "stats");
    lua_newtable(L);
    for (auto& p : r.graph().passes())
        for (auto& [key, v] : p->stats()) {
            lua_pushnumber(L, v);
            lua_setfield(L, -2, (p->name() + "." + key).c_str());
        }
    if (const scene::SceneGpu* s = r.scene()) {
        // The scene's last per-frame update (moving and deforming shapes), CPU milliseconds.
        const auto& st = s->stats();
        const std::pair<const char*, double> values[] = {{"scene.triangles", double(st.triangles)},
                                                         {"scene.updateMs", st.updateMs},
                                                         {"scene.bvhBuildMs", st.bvhBuildMs},
                                                         {"scene.adjacencyMs", st.adjacencyMs}};
        for (auto& [key, v] : values) {
            lua_pushnumber(L, v);
            lua_setfield(L, -2, key);
        }
    }
    return 1;
}

// ---------------------------------------------------------------------------------------------
// Image methods. Pixel coordinates are 0-based, x to the right, y down (row 0 = top).

ImageData& selfImage(lua_State* L, const char* method) {
    return imageArg(L, 1, fmt::format("img:{}", method), "self (call it with ':')");
}

void checkPixel(const ImageData& img, int64_t x, int64_t y, const std::string& fn) {
    if (x < 0 || y < 0 || x >= int64_t(img.width) || y >= int64_t(img.height))
        throw ScriptError(fmt::format("{}: pixel ({}, {}) is outside the {}x{} image (0-based)", fn,
                                      x, y, img.width, img.height));
}

// RGBA of a pixel whatever the channel count (grey -> r=g=b; missing alpha -> 1).
std::array<float, 4> rgba(const ImageData& img, uint32_t x, uint32_t y) {
    std::array<float, 4> v{0, 0, 0, 1};
    uint32_t ch = img.channels;
    if (ch == 1) {
        v[0] = v[1] = v[2] = img.at(x, y, 0);
    } else {
        for (uint32_t c = 0; c < std::min(ch, 4u); ++c) v[c] = img.at(x, y, c);
    }
    return v;
}

int iWidth(lua_State* L) {
    lua_pushinteger(L, selfImage(L, "width").width);
    return 1;
}

int iHeight(lua_State* L) {
    lua_pushinteger(L, selfImage(L, "height").height);
    return 1;
}

int iChannels(lua_State* L) {
    lua_pushinteger(L, selfImage(L, "channels").channels);
    return 1;
}

int iGet(lua_State* L) {
    ImageData& img = selfImage(L, "get");
    int64_t x = argInteger(L, 2, "img:get", "x"), y = argInteger(L, 3, "img:get", "y");
    checkPixel(img, x, y, "img:get");
    for (float v : rgba(img, uint32_t(x), uint32_t(y))) lua_pushnumber(L, v);
    return 4;
}

int iSet(lua_State* L) {
    ImageData& img = selfImage(L, "set");
    int64_t x = argInteger(L, 2, "img:set", "x"), y = argInteger(L, 3, "img:set", "y");
    checkPixel(img, x, y, "img:set");
    float v[4] = {0, 0, 0, 1};
    const char* names[4] = {"r", "g", "b", "a"};
    for (int c = 0; c < 4; ++c) {
        if (c == 3 && lua_isnoneornil(L, 7)) break;
        v[c] = float(argNumber(L, 4 + c, "img:set", names[c]));
    }
    if (img.channels == 1)
        img.at(uint32_t(x), uint32_t(y), 0) = v[0];
    else
        for (uint32_t c = 0; c < std::min(img.channels, 4u); ++c)
            img.at(uint32_t(x), uint32_t(y), c) = v[c];
    return 0;
}

int iMean(lua_State* L) {
    ImageData& img = selfImage(L, "mean");
    double sum[3] = {0, 0, 0};
    for (uint32_t y = 0; y < img.height; ++y)
        for (uint32_t x = 0; x < img.width; ++x) {
            auto v = rgba(img, x, y);
            for (int c = 0; c < 3; ++c) sum[c] += v[c];
        }
    double n = std::max(1.0, double(img.width) * img.height);
    for (double s : sum) lua_pushnumber(L, s / n);
    return 3;
}

int iCrop(lua_State* L) {
    ImageData& img = selfImage(L, "crop");
    const std::string fn = "img:crop";
    int64_t x = argInteger(L, 2, fn, "x", 0), y = argInteger(L, 3, fn, "y", 0);
    int64_t w = argInteger(L, 4, fn, "w", 1), h = argInteger(L, 5, fn, "h", 1);
    if (x + w > int64_t(img.width) || y + h > int64_t(img.height))
        throw ScriptError(fmt::format("{}: rectangle ({}, {}) size {}x{} exceeds the {}x{} image",
                                      fn, x, y, w, h, img.width, img.height));
    ImageData out = ImageData::make(uint32_t(w), uint32_t(h), img.channels);
    for (int64_t j = 0; j < h; ++j)
        for (int64_t i = 0; i < w; ++i)
            for (uint32_t c = 0; c < img.channels; ++c)
                out.at(uint32_t(i), uint32_t(j), c) = img.at(uint32_t(x + i), uint32_t(y + j), c);
    pushImage(L, std::move(out));
    return 1;
}

int iWrite(lua_State* L) {
    ImageData& img = selfImage(L, "write");
    std::string path = argString(L, 2, "img:write", "the file path (.exr, .hdr, .png, .jpg)");
    writeImage(path, img);
    return 0;
}

int iToString(lua_State* L) {
    auto** p = static_cast<ImageData**>(luaL_testudata(L, 1, kImageMeta));
    std::string s = p && *p ? fmt::format("loom.Image {}x{} ({} channels)", (*p)->width,
                                          (*p)->height, (*p)->channels)
                            : "loom.Image (freed)";
    lua_pushstring(L, s.c_str());
    return 1;
}

// ---------------------------------------------------------------------------------------------
// loom.* functions: images and metrics

int lReadImage(lua_State* L) {
    std::string path = argString(L, 1, "loom.read_image", "the file path");
    bool linearize = lua_toboolean(L, 2);
    pushImage(L,
              readImage(resolveInput(host(L), path, "loom.read_image", "image file"), linearize));
    return 1;
}

int lNewImage(lua_State* L) {
    const std::string fn = "loom.new_image";
    auto w = argInteger(L, 1, fn, "the width", 1, 16384);
    auto h = argInteger(L, 2, fn, "the height", 1, 16384);
    ImageData img = ImageData::make(uint32_t(w), uint32_t(h), 4, 0.0f);
    float fill[4] = {0, 0, 0, 1};
    const char* names[4] = {"r", "g", "b", "a"};
    for (int c = 0; c < 4; ++c)
        if (!lua_isnoneornil(L, 3 + c)) fill[c] = float(argNumber(L, 3 + c, fn, names[c]));
    for (size_t p = 0; p < size_t(w) * size_t(h); ++p)
        for (int c = 0; c < 4; ++c) img.pixels[p * 4 + c] = fill[c];
    pushImage(L, std::move(img));
    return 1;
}

template <Metric M>
int lMetric(lua_State* L) {
    std::string fn = std::string("loom.metrics.") + metricName(M);
    ImageData& a = imageArg(L, 1, fn, "the image (argument 1)");
    ImageData& b = imageArg(L, 2, fn, "the reference (argument 2)");
    double eps = lua_isnoneornil(L, 3) ? 1e-2 : argNumber(L, 3, fn, "eps");
    lua_pushnumber(L, computeMetric(M, a, b, eps));
    return 1;
}

// loom.metrics.flip(image, reference [, {ppd=, ldr=}]): mean FLIP (Andersson et al. 2020) and
// the per-pixel error image. Default: HDR-FLIP of linear images; ldr = true: LDR-FLIP of sRGB
// images in [0, 1]. ppd: pixels per degree of the observer (default 67, the papers').
int lFlip(lua_State* L) {
    const std::string fn = "loom.metrics.flip";
    ImageData& a = imageArg(L, 1, fn, "the image (argument 1)");
    ImageData& b = imageArg(L, 2, fn, "the reference (argument 2)");
    double ppd = kFlipDefaultPpd;
    bool ldr = false;
    if (!lua_isnoneornil(L, 3)) {
        if (lua_type(L, 3) != LUA_TTABLE)
            throw ScriptError(fn + ": options must be a table {ppd=, ldr=}, got " + describe(L, 3));
        checkKeys(L, 3, fn, {"ppd", "ldr"});
        ppd = optNumberField(L, 3, "ppd", fn).value_or(ppd);
        ldr = optBoolField(L, 3, "ldr", fn, false);
        if (!(ppd > 0.0 && ppd < 1e4))
            throw ScriptError(fmt::format("{}: 'ppd' must be in (0, 10000), got {}", fn, ppd));
    }
    if (a.width != b.width || a.height != b.height)
        throw ScriptError(fmt::format("{}: image is {}x{} but reference is {}x{}", fn, a.width,
                                      a.height, b.width, b.height));
    ImageData err = ldr ? flipLdr(a, b, ppd) : flipHdr(a, b, ppd);
    lua_pushnumber(L, meanOf(err));
    pushImage(L, std::move(err));
    return 2;
}

// Per-pixel error mapped to false colour; max defaults to the 99th percentile of the errors.
int lErrorImage(lua_State* L) {
    const std::string fn = "loom.metrics.error_image";
    ImageData& a = imageArg(L, 1, fn, "the image (argument 1)");
    ImageData& b = imageArg(L, 2, fn, "the reference (argument 2)");
    Metric m = parseMetric(lua_isnoneornil(L, 3) ? "relmse" : argString(L, 3, fn, "the metric"));
    if (a.width != b.width || a.height != b.height)
        throw ScriptError(fmt::format("{}: image is {}x{} but reference is {}x{}", fn, a.width,
                                      a.height, b.width, b.height));
    uint32_t ch = std::min(a.channels, b.channels);
    ImageData err = ImageData::make(a.width, a.height, 1);
    for (size_t p = 0; p < size_t(a.width) * a.height; ++p) {
        double e = pixelError(m, &a.pixels[p * a.channels], &b.pixels[p * b.channels], ch, 1e-2);
        err.pixels[p] = float(m == Metric::RMSE ? std::sqrt(e) : e);
    }
    double maxValue = 0;
    if (!lua_isnoneornil(L, 4)) {
        maxValue = argNumber(L, 4, fn, "max");
    } else {
        std::vector<float> sorted = err.pixels;
        std::sort(sorted.begin(), sorted.end());
        maxValue = sorted.empty() ? 0 : sorted[size_t(0.99 * double(sorted.size() - 1))];
    }
    if (!(maxValue > 0)) maxValue = 1;
    bool logScale = lua_toboolean(L, 5);
    pushImage(L, falseColor(err, float(maxValue), logScale));
    return 1;
}

// ---------------------------------------------------------------------------------------------
// Results: CSV, JSON, plots

std::string formatNumber(lua_State* L, int i) {
    if (lua_isinteger(L, i)) return std::to_string(lua_tointeger(L, i));
    double v = lua_tonumber(L, i);
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    char buf[64];
    auto res = std::to_chars(buf, buf + sizeof(buf), v);  // shortest round trip
    return std::string(buf, res.ptr);
}

// loom.write_csv(path, rows [, {columns = {...}}]): header = union of the rows' keys; listed
// columns first, then `index`, then the rest in alphabetical order.
int lWriteCsv(lua_State* L) {
    const std::string fn = "loom.write_csv";
    std::string path = argString(L, 1, fn, "the path");
    if (lua_type(L, 2) != LUA_TTABLE)
        throw ScriptError(fn + ": rows must be an array of tables, got " + describe(L, 2));
    std::vector<std::string> columns;
    if (!lua_isnoneornil(L, 3)) {
        if (lua_type(L, 3) != LUA_TTABLE) throw ScriptError(fn + ": options must be a table");
        checkKeys(L, 3, fn + " options", {"columns"});
        if (rawField(L, 3, "columns") == LUA_TTABLE) {
            lua_Integer n = lua_Integer(lua_rawlen(L, -1));
            for (lua_Integer k = 1; k <= n; ++k) {
                lua_rawgeti(L, -1, k);
                columns.push_back(argString(L, -1, fn, fmt::format("columns[{}]", k)));
                lua_pop(L, 1);
            }
        }
        lua_pop(L, 1);
    }
    lua_Integer n = lua_Integer(lua_rawlen(L, 2));
    std::set<std::string> keys;
    std::vector<std::map<std::string, std::string>> rows;
    for (lua_Integer k = 1; k <= n; ++k) {
        lua_rawgeti(L, 2, k);
        int row = lua_gettop(L);
        if (lua_type(L, row) != LUA_TTABLE)
            throw ScriptError(
                fmt::format("{}: rows[{}] must be a table, got {}", fn, k, describe(L, row)));
        std::map<std::string, std::string> cells;
        lua_pushnil(L);
        while (lua_next(L, row)) {
            if (lua_type(L, -2) != LUA_TSTRING)
                throw ScriptError(
                    fmt::format("{}: rows[{}] has a non-string key {}; rows are "
                                "tables like {{name = value}}",
                                fn, k, describe(L, -2)));
            std::string key = lua_tostring(L, -2);
            std::string cell;
            switch (lua_type(L, -1)) {
                case LUA_TNUMBER:
                    cell = formatNumber(L, -1);
                    break;
                case LUA_TSTRING:
                    cell = lua_tostring(L, -1);
                    break;
                case LUA_TBOOLEAN:
                    cell = lua_toboolean(L, -1) ? "true" : "false";
                    break;
                default:
                    throw ScriptError(fmt::format(
                        "{}: rows[{}].{} is a {}; CSV cells must be numbers, strings or booleans",
                        fn, k, key, luaL_typename(L, -1)));
            }
            keys.insert(key);
            cells[key] = cell;
            lua_pop(L, 1);
        }
        rows.push_back(std::move(cells));
        lua_pop(L, 1);
    }
    CsvTable table;
    table.header = columns;
    auto listed = [&](const std::string& k) {
        return std::find(table.header.begin(), table.header.end(), k) != table.header.end();
    };
    if (keys.count("index") && !listed("index")) table.header.push_back("index");
    for (auto& k : keys)
        if (!listed(k)) table.header.push_back(k);
    for (auto& cells : rows) {
        std::vector<std::string> rec;
        for (auto& h : table.header) rec.push_back(cells.count(h) ? cells[h] : "");
        table.rows.push_back(std::move(rec));
    }
    Host& h = host(L);
    if (h.options.shardCount > 1) {
        // A shard writes its part; the merge (loom merge, or a sweep's merge job) joins them.
        table.sweep = SweepPart{h.options.sweepId.empty() ? "unnamed" : h.options.sweepId,
                                h.options.shardIndex, h.options.shardCount};
        std::string part = csvPartPath(path, h.options.shardIndex);
        writeCsv(part, table);
        logInfo("{}: shard {}/{} of {}", part, h.options.shardIndex, h.options.shardCount, path);
        if (!h.options.sweepDir.empty() &&
            h.sweepCsvs.insert(fs::absolute(path).lexically_normal().string()).second) {
            std::string list;
            for (auto& c : h.sweepCsvs) list += c + "\n";
            writeTextFileAtomic(
                fmt::format("{}/parts/task-{}.txt", h.options.sweepDir, h.options.shardIndex),
                "sweep manifest", list);
        }
    } else {
        writeCsv(path, table);
    }
    lua_pushinteger(L, lua_Integer(rows.size()));
    return 1;
}

// loom.read_csv(path) -> array of rows; fields that parse completely as numbers are numbers.
int lReadCsv(lua_State* L) {
    std::string path = argString(L, 1, "loom.read_csv", "the path");
    CsvTable t = readCsv(resolveInput(host(L), path, "loom.read_csv", "CSV file"));
    lua_createtable(L, int(t.rows.size()), 0);
    for (size_t r = 0; r < t.rows.size(); ++r) {
        lua_createtable(L, 0, int(t.header.size()));
        for (size_t c = 0; c < t.header.size(); ++c) {
            const std::string& f = t.rows[r][c];
            if (f.empty()) continue;
            if (lua_stringtonumber(L, f.c_str()) == 0) lua_pushstring(L, f.c_str());
            lua_setfield(L, -2, t.header[c].c_str());
        }
        lua_rawseti(L, -2, lua_Integer(r + 1));
    }
    return 1;
}

int lWriteJson(lua_State* L) {
    const std::string fn = "loom.write_json";
    std::string path = argString(L, 1, fn, "the path");
    json j = toJson(L, 2, fn);
    writeTextFileAtomic(path, "JSON file", j.dump(2) + "\n");
    return 0;
}

int lReadJson(lua_State* L) {
    std::string path = argString(L, 1, "loom.read_json", "the path");
    pushJson(L,
             JsonSource::load(resolveInput(host(L), path, "loom.read_json", "JSON file")).root());
    return 1;
}

int lJsonDecode(lua_State* L) {
    std::string text = argString(L, 1, "loom.json_decode", "the text");
    pushJson(L, JsonSource::parse(text, "json_decode").root());
    return 1;
}

int lJsonEncode(lua_State* L) {
    std::string s = toJson(L, 1, "loom.json_encode").dump();
    lua_pushlstring(L, s.data(), s.size());
    return 1;
}

int lPlot(lua_State* L) {
    const std::string fn = "loom.plot";
    if (lua_type(L, 1) != LUA_TTABLE)
        throw ScriptError(fn +
                          ": expects a table {path=, title=, x_label=, y_label=, log_x=, "
                          "log_y=, series={{name=, x={...}, y={...}}, ...}}");
    checkKeys(
        L, 1, fn,
        {"path", "title", "x_label", "y_label", "log_x", "log_y", "series", "width", "height"});
    PlotSpec spec;
    auto path = optStringField(L, 1, "path", fn);
    if (!path) throw ScriptError(fn + ": 'path' is required (writes PATH.svg and PATH.png)");
    spec.title = optStringField(L, 1, "title", fn).value_or("");
    spec.xLabel = optStringField(L, 1, "x_label", fn).value_or("");
    spec.yLabel = optStringField(L, 1, "y_label", fn).value_or("");
    spec.logX = optBoolField(L, 1, "log_x", fn, false);
    spec.logY = optBoolField(L, 1, "log_y", fn, false);
    spec.width = uint32_t(optIntegerField(L, 1, "width", fn, 200, 8192).value_or(800));
    spec.height = uint32_t(optIntegerField(L, 1, "height", fn, 150, 8192).value_or(520));
    if (rawField(L, 1, "series") != LUA_TTABLE)
        throw ScriptError(fn + ": 'series' must be an array of {name=, x={...}, y={...}}");
    int series = lua_gettop(L);
    lua_Integer n = lua_Integer(lua_rawlen(L, series));
    for (lua_Integer k = 1; k <= n; ++k) {
        lua_rawgeti(L, series, k);
        int s = lua_gettop(L);
        std::string sfn = fmt::format("{}: series[{}]", fn, k);
        if (lua_type(L, s) != LUA_TTABLE) throw ScriptError(sfn + " must be a table");
        checkKeys(L, s, sfn, {"name", "x", "y"});
        PlotSeries ps;
        ps.name = optStringField(L, s, "name", sfn).value_or("");
        rawField(L, s, "x");
        ps.x = numberArray(L, -1, sfn, "x");
        lua_pop(L, 1);
        rawField(L, s, "y");
        ps.y = numberArray(L, -1, sfn, "y");
        lua_pop(L, 1);
        spec.series.push_back(std::move(ps));
        lua_pop(L, 1);
    }
    lua_pop(L, 1);
    auto [svg, png] = writePlot(*path, spec);
    lua_pushstring(L, svg.c_str());
    lua_pushstring(L, png.c_str());
    return 2;
}

// ---------------------------------------------------------------------------------------------
// Progress, arguments, sweeps

std::string formatDuration(double seconds) {
    long long s = std::max(0LL, (long long)std::llround(seconds));
    if (s >= 3600) return fmt::format("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60);
    return fmt::format("{}:{:02}", s / 60, s % 60);
}

// LOOM_PROGRESS=1 forces progress lines (one per second, no terminal codes), 0 silences them;
// otherwise a bar is drawn only when stderr is a terminal.
int lProgress(lua_State* L) {
    const std::string fn = "loom.progress";
    double i = argNumber(L, 1, fn, "i"), n = argNumber(L, 2, fn, "n");
    std::string label = lua_isnoneornil(L, 3) ? "progress" : argString(L, 3, fn, "the label");
    const char* env = std::getenv("LOOM_PROGRESS");
    bool tty = isatty(STDERR_FILENO) != 0;
    bool forced = env && std::string(env) == "1";
    if ((env && std::string(env) == "0") || (!tty && !forced)) return 0;
    auto& p = host(L).progress;
    auto now = Clock::now();
    if (!p.active || label != p.label || i < p.last) {
        p.active = true;
        p.label = label;
        p.start = now;
        p.lastPrint = Clock::time_point{};
    }
    p.last = i;
    bool done = i >= n;
    double sinceLast = std::chrono::duration<double>(now - p.lastPrint).count();
    if (!done && sinceLast < (tty ? 0.1 : 1.0)) return 0;
    p.lastPrint = now;
    double elapsed = std::chrono::duration<double>(now - p.start).count();
    double frac = n > 0 ? std::clamp(i / n, 0.0, 1.0) : 1.0;
    std::string eta = done ? "done" : i > 0 ? formatDuration(elapsed / i * (n - i)) : "--:--";
    constexpr int kBar = 30;
    int filled = int(frac * kBar);
    std::string line = fmt::format("{} [{}{}] {}/{} {:3d}%  {} elapsed  ETA {}", label,
                                   std::string(filled, '#'), std::string(kBar - filled, '.'), i, n,
                                   int(frac * 100), formatDuration(elapsed), eta);
    if (tty)
        std::fprintf(stderr, "\r%s\x1b[K%s", line.c_str(), done ? "\n" : "");
    else
        std::fprintf(stderr, "%s\n", line.c_str());
    std::fflush(stderr);
    if (done) p.active = false;
    return 0;
}

// loom.arg(name, default): a NAME=VALUE / --NAME VALUE script argument converted to the type
// of `default` (number, integer, boolean, string, or an array from "1,2,4").
int lArg(lua_State* L) {
    const std::string fn = "loom.arg";
    std::string name = argString(L, 1, fn, "the argument name");
    Host& h = host(L);
    auto it = h.named.find(name);
    if (it == h.named.end()) {
        lua_settop(L, 2);
        return 1;
    }
    const std::string& text = it->second;
    auto bad = [&](const char* expected) {
        return ScriptError(
            fmt::format("script argument '{}' expects {}, got '{}'", name, expected, text));
    };
    auto pushAs = [&](int type, bool integer, const std::string& s) {
        if (type == LUA_TNUMBER) {
            if (lua_stringtonumber(L, s.c_str()) == 0)
                throw bad(integer ? "an integer" : "a number");
            if (integer && !lua_isinteger(L, -1)) throw bad("an integer");
        } else if (type == LUA_TBOOLEAN) {
            if (s == "true" || s == "1" || s == "yes" || s == "on")
                lua_pushboolean(L, 1);
            else if (s == "false" || s == "0" || s == "no" || s == "off")
                lua_pushboolean(L, 0);
            else
                throw bad("a boolean (true/false)");
        } else {
            lua_pushlstring(L, s.data(), s.size());
        }
    };
    int type = lua_type(L, 2);
    if (type == LUA_TTABLE) {
        lua_rawgeti(L, 2, 1);
        int elemType = lua_type(L, -1);
        bool integer = elemType == LUA_TNUMBER && lua_isinteger(L, -1);
        lua_pop(L, 1);
        lua_newtable(L);
        std::stringstream ss(text);
        std::string item;
        int k = 1;
        while (std::getline(ss, item, ',')) {
            pushAs(elemType == LUA_TNIL ? LUA_TSTRING : elemType, integer, item);
            lua_rawseti(L, -2, k++);
        }
        return 1;
    }
    pushAs(type, type == LUA_TNUMBER && lua_isinteger(L, 2), text);
    return 1;
}

int sweepNext(lua_State* L) {
    // Upvalues: values table, next 1-based index, step (shard count).
    lua_Integer idx = lua_tointeger(L, lua_upvalueindex(2));
    lua_Integer step = lua_tointeger(L, lua_upvalueindex(3));
    if (idx > lua_Integer(lua_rawlen(L, lua_upvalueindex(1)))) return 0;
    lua_pushinteger(L, idx + step);
    lua_replace(L, lua_upvalueindex(2));
    lua_pushinteger(L, idx);
    lua_rawgeti(L, lua_upvalueindex(1), idx);
    return 2;
}

// for index, value in loom.sweep{name=, values={...}}: this shard's values (round robin).
int lSweep(lua_State* L) {
    const std::string fn = "loom.sweep";
    if (lua_type(L, 1) != LUA_TTABLE)
        throw ScriptError(fn + ": expects a table {name=, values={...}}, got " + describe(L, 1));
    checkKeys(L, 1, fn, {"name", "values"});
    std::string name = optStringField(L, 1, "name", fn).value_or("sweep");
    if (rawField(L, 1, "values") != LUA_TTABLE || lua_rawlen(L, -1) == 0)
        throw ScriptError(fn + ": 'values' must be a non-empty array");
    Host& h = host(L);
    size_t total = lua_rawlen(L, -1);
    if (h.options.phase == "merge") {  // the plot step reads the merged CSV instead
        logInfo("sweep '{}': merge phase, no values run", name);
        lua_pushinteger(L, lua_Integer(total) + 1);
        lua_pushinteger(L, 1);
        lua_pushcclosure(L, sweepNext, 3);
        return 1;
    }
    if (h.options.shardCount > 1) {
        size_t mine =
            total > h.options.shardIndex
                ? (total - h.options.shardIndex + h.options.shardCount - 1) / h.options.shardCount
                : 0;
        logInfo("sweep '{}': shard {}/{} runs {} of {} values", name, h.options.shardIndex,
                h.options.shardCount, mine, total);
    }
    lua_pushinteger(L, lua_Integer(h.options.shardIndex) + 1);
    lua_pushinteger(L, lua_Integer(h.options.shardCount));
    lua_pushcclosure(L, sweepNext, 3);
    return 1;
}

int lTimeMs(lua_State* L) {
    lua_pushnumber(L,
                   std::chrono::duration<double, std::milli>(Clock::now() - host(L).start).count());
    return 1;
}

int lPassTypes(lua_State* L) {
    pushJson(L, json(PassRegistry::instance().types()));
    return 1;
}

// ---------------------------------------------------------------------------------------------
// Registration

const luaL_Reg kRendererMethods[] = {{"frame", guarded<rFrame>},
                                     {"frames", guarded<rFrames>},
                                     {"run_for_ms", guarded<rRunForMs>},
                                     {"reset", guarded<rReset>},
                                     {"close", guarded<rClose>},
                                     {"width", guarded<rWidth>},
                                     {"height", guarded<rHeight>},
                                     {"resize", guarded<rResize>},
                                     {"frame_count", guarded<rFrameCount>},
                                     {"set_seed", guarded<rSetSeed>},
                                     {"set", guarded<rSet>},
                                     {"get", guarded<rGet>},
                                     {"params", guarded<rParams>},
                                     {"add_pass", guarded<rAddPass>},
                                     {"remove_pass", guarded<rRemovePass>},
                                     {"connect", guarded<rConnect>},
                                     {"disconnect", guarded<rDisconnect>},
                                     {"mark_output", guarded<rMarkOutput>},
                                     {"unmark_output", guarded<rUnmarkOutput>},
                                     {"save_graph", guarded<rSaveGraph>},
                                     {"passes", guarded<rPasses>},
                                     {"outputs", guarded<rOutputs>},
                                     {"camera", guarded<rCamera>},
                                     {"camera_path", guarded<rCameraPath>},
                                     {"set_time", guarded<rSetTime>},
                                     {"shutter", guarded<rShutter>},
                                     {"time", guarded<rTime>},
                                     {"image", guarded<rImage>},
                                     {"capture", guarded<rCapture>},
                                     {"timings", guarded<rTimings>},
                                     {"stats", guarded<rStats>},
                                     {nullptr, nullptr}};

const luaL_Reg kImageMethods[] = {
    {"width", guarded<iWidth>}, {"height", guarded<iHeight>}, {"channels", guarded<iChannels>},
    {"get", guarded<iGet>},     {"set", guarded<iSet>},       {"mean", guarded<iMean>},
    {"crop", guarded<iCrop>},   {"write", guarded<iWrite>},   {nullptr, nullptr}};

const luaL_Reg kLoomFunctions[] = {{"renderer", guarded<lRenderer>},
                                   {"read_image", guarded<lReadImage>},
                                   {"new_image", guarded<lNewImage>},
                                   {"write_csv", guarded<lWriteCsv>},
                                   {"read_csv", guarded<lReadCsv>},
                                   {"write_json", guarded<lWriteJson>},
                                   {"read_json", guarded<lReadJson>},
                                   {"json_decode", guarded<lJsonDecode>},
                                   {"json_encode", guarded<lJsonEncode>},
                                   {"plot", guarded<lPlot>},
                                   {"progress", guarded<lProgress>},
                                   {"arg", guarded<lArg>},
                                   {"sweep", guarded<lSweep>},
                                   {"time_ms", guarded<lTimeMs>},
                                   {"pass_types", guarded<lPassTypes>},
                                   {nullptr, nullptr}};

const luaL_Reg kMetricFunctions[] = {{"mse", guarded<lMetric<Metric::MSE>>},
                                     {"relmse", guarded<lMetric<Metric::RelMSE>>},
                                     {"rmse", guarded<lMetric<Metric::RMSE>>},
                                     {"mape", guarded<lMetric<Metric::MAPE>>},
                                     {"error_image", guarded<lErrorImage>},
                                     {"flip", guarded<lFlip>},
                                     {nullptr, nullptr}};

int gcRenderer(lua_State* L) {
    return gcOwned<Renderer>(L, kRendererMeta);
}
int gcImage(lua_State* L) {
    return gcOwned<ImageData>(L, kImageMeta);
}

void newMetatable(lua_State* L, const char* name, const luaL_Reg* methods, lua_CFunction gc,
                  lua_CFunction toString) {
    luaL_newmetatable(L, name);
    lua_newtable(L);
    luaL_setfuncs(L, methods, 0);
    lua_setfield(L, -2, "__index");
    lua_pushcfunction(L, gc);
    lua_setfield(L, -2, "__gc");
    lua_pushcfunction(L, toString);
    lua_setfield(L, -2, "__tostring");
    lua_pop(L, 1);
}

// Runs protected (lua_pcall) with the Host as light userdata: builds the module, loom.args,
// loom.shard and the global `arg`. Only Lua API calls here, no C++ objects.
int openModule(lua_State* L) {
    Host* h = static_cast<Host*>(lua_touserdata(L, 1));
    lua_pushlightuserdata(L, h);
    lua_setfield(L, LUA_REGISTRYINDEX, kHostKey);
    newMetatable(L, kRendererMeta, kRendererMethods, gcRenderer, guarded<rToString>);
    newMetatable(L, kImageMeta, kImageMethods, gcImage, guarded<iToString>);

    luaL_newlib(L, kLoomFunctions);
    luaL_newlib(L, kMetricFunctions);
    lua_setfield(L, -2, "metrics");
    lua_newtable(L);  // loom.args: positional strings and NAME=VALUE fields
    lua_Integer k = 1;
    for (const auto& a : h->options.args) {
        lua_pushlstring(L, a.data(), a.size());
        lua_rawseti(L, -2, k++);
    }
    for (const auto& [name, value] : h->named) {
        lua_pushlstring(L, value.data(), value.size());
        lua_setfield(L, -2, name.c_str());
    }
    lua_setfield(L, -2, "args");
    lua_createtable(L, 0, 2);
    lua_pushinteger(L, lua_Integer(h->options.shardIndex));
    lua_setfield(L, -2, "index");
    lua_pushinteger(L, lua_Integer(h->options.shardCount));
    lua_setfield(L, -2, "count");
    lua_setfield(L, -2, "shard");
    lua_pushstring(L, h->options.phase.c_str());
    lua_setfield(L, -2, "phase");
    lua_pushstring(L, "0.1");
    lua_setfield(L, -2, "version");

    lua_pushvalue(L, -1);
    lua_setglobal(L, "loom");
    luaL_getsubtable(L, LUA_REGISTRYINDEX, LUA_LOADED_TABLE);
    lua_pushvalue(L, -2);
    lua_setfield(L, -2, "loom");  // require("loom") returns the module
    return 0;
}

// Message handler: the error message plus a traceback (luaL_traceback).
int messageHandler(lua_State* L) {
    const char* msg = lua_tostring(L, 1);
    if (!msg) {
        if (luaL_callmeta(L, 1, "__tostring") && lua_type(L, -1) == LUA_TSTRING)
            msg = lua_tostring(L, -1);
        else
            msg = lua_pushfstring(L, "(error object is a %s value)", luaL_typename(L, 1));
    }
    luaL_traceback(L, L, msg, 1);
    return 1;
}

void parseNamedArgs(const std::vector<std::string>& args,
                    std::map<std::string, std::string>& named) {
    for (size_t i = 0; i < args.size(); ++i) {
        std::string a = args[i];
        bool dashed = a.rfind("--", 0) == 0;
        if (dashed) a = a.substr(2);
        auto eq = a.find('=');
        if (eq != std::string::npos && eq > 0) {
            named[a.substr(0, eq)] = a.substr(eq + 1);
        } else if (dashed && !a.empty()) {
            bool hasValue = i + 1 < args.size() && args[i + 1].rfind("--", 0) != 0 &&
                            args[i + 1].find('=') == std::string::npos;
            named[a] = hasValue ? args[++i] : "true";
        }
    }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// LuaRuntime

struct LuaRuntime::Impl {
    Host host;  // outlives the state: renderers finalised by lua_close() use its contexts
    lua_State* L = nullptr;
    std::string lastError;

    int finish(int status, const std::string& what) {
        if (status == LUA_OK) {
            int code = lua_isinteger(L, -1) ? int(lua_tointeger(L, -1)) : 0;
            lua_settop(L, 0);
            lastError.clear();
            return code;
        }
        const char* msg = lua_tostring(L, -1);
        lastError = msg ? msg : ("error running " + what);
        lua_settop(L, 0);
        if (host.options.printErrors) {
            std::fflush(stdout);
            std::fprintf(stderr, "error: %s\n", lastError.c_str());
        }
        return 2;
    }

    int run(int loadStatus, const std::string& what) {
        if (loadStatus != LUA_OK) return finish(loadStatus, what);
        lua_pushcfunction(L, messageHandler);
        lua_insert(L, -2);
        for (auto& a : host.options.args) lua_pushlstring(L, a.data(), a.size());
        int status = lua_pcall(L, int(host.options.args.size()), 1, 1);
        if (status == LUA_OK) lua_remove(L, 1);  // the handler; the result stays on top
        return finish(status, what);
    }
};

LuaRuntime::LuaRuntime(Options options) : mImpl(std::make_unique<Impl>()) {
    if (options.shardCount == 0 || options.shardIndex >= options.shardCount)
        throw UserError(fmt::format("shard {}/{}: expected I/N with 0 <= I < N", options.shardIndex,
                                    options.shardCount));
    if (options.phase != "run" && options.phase != "merge")
        throw UserError("--phase must be run or merge, got '" + options.phase + "'");
    mImpl->host.options = std::move(options);
    parseNamedArgs(mImpl->host.options.args, mImpl->host.named);
    mImpl->L = luaL_newstate();
    if (!mImpl->L) throw std::runtime_error("cannot create a Lua state (out of memory)");
    lua_State* L = mImpl->L;
    luaL_openlibs(L);
    lua_pushcfunction(L, openModule);
    lua_pushlightuserdata(L, &mImpl->host);
    if (lua_pcall(L, 1, 0, 0) != LUA_OK) {
        std::string msg = lua_tostring(L, -1) ? lua_tostring(L, -1) : "?";
        lua_close(L);
        mImpl->L = nullptr;
        throw std::runtime_error("cannot open the loom Lua module: " + msg);
    }
}

LuaRuntime::~LuaRuntime() {
    if (mImpl->L) lua_close(mImpl->L);
}

int LuaRuntime::runFile(const std::string& path) {
    lua_State* L = mImpl->L;
    mImpl->host.scriptDir = fs::path(path).parent_path().string();
    // Lua's standalone convention: arg[0] is the script, arg[1..] its arguments.
    lua_createtable(L, int(mImpl->host.options.args.size()), 1);
    lua_pushstring(L, path.c_str());
    lua_rawseti(L, -2, 0);
    for (size_t i = 0; i < mImpl->host.options.args.size(); ++i) {
        lua_pushstring(L, mImpl->host.options.args[i].c_str());
        lua_rawseti(L, -2, lua_Integer(i + 1));
    }
    lua_setglobal(L, "arg");
    // require("name") also finds modules next to the script (scripts/util.lua).
    lua_getglobal(L, "package");
    lua_getfield(L, -1, "path");
    std::string dir = mImpl->host.scriptDir.empty() ? "." : mImpl->host.scriptDir;
    std::string searchPath = dir + "/?.lua;" + (lua_tostring(L, -1) ? lua_tostring(L, -1) : "");
    lua_pop(L, 1);
    lua_pushstring(L, searchPath.c_str());
    lua_setfield(L, -2, "path");
    lua_pop(L, 1);
    return mImpl->run(luaL_loadfile(L, path.c_str()), path);
}

int LuaRuntime::runString(const std::string& code, const std::string& chunkName) {
    lua_State* L = mImpl->L;
    return mImpl->run(luaL_loadbuffer(L, code.data(), code.size(), chunkName.c_str()), chunkName);
}

const std::string& LuaRuntime::lastError() const {
    return mImpl->lastError;
}

void parseShard(const std::string& text, uint32_t& index, uint32_t& count) {
    auto slash = text.find('/');
    auto bad = [&] {
        return UserError("--shard expects I/N with 0 <= I < N (e.g. 0/4), got '" + text + "'");
    };
    if (slash == std::string::npos) throw bad();
    try {
        size_t p1 = 0, p2 = 0;
        std::string a = text.substr(0, slash), b = text.substr(slash + 1);
        long long i = std::stoll(a, &p1), n = std::stoll(b, &p2);
        if (p1 != a.size() || p2 != b.size() || i < 0 || n < 1 || i >= n || n > 1 << 20)
            throw bad();
        index = uint32_t(i);
        count = uint32_t(n);
    } catch (const std::logic_error&) {
        throw bad();
    }
}

}  // namespace loom::script
