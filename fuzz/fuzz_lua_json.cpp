// The Lua argument converters: text -> json_decode (JSON to Lua tables) -> json_encode (Lua
// tables back to JSON), which must round-trip whatever they accept.
#include "core/script/LuaBindings.h"
#include "fuzz/FuzzSupport.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    return loom::fuzz::guard([&] {
        loom::script::LuaRuntime::Options o;
        o.args = {std::string(reinterpret_cast<const char*>(data), size)};
        o.printErrors = false;
        loom::script::LuaRuntime lua(o);
        // Decoding and encoding may refuse (a named error); what they accept must round-trip.
        int rc = lua.runString(
            "local ok, v = pcall(loom.json_decode, loom.args[1])\n"
            "if not ok then return end\n"
            "local ok2, text = pcall(loom.json_encode, v)\n"
            "if not ok2 then return end\n"
            "assert(loom.json_encode(loom.json_decode(text)) == text, 'no round trip')\n",
            "=fuzz");
        if (rc != 0) std::abort();
    });
}
