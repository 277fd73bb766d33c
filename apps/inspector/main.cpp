// loom-inspector: the live GUI graph inspector. Usage and input errors exit 2 with one clear
// message; internal errors exit 1.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "apps/CliArgs.h"
#include "apps/inspector/InspectorApp.h"
#include "core/util/Log.h"

using namespace loom;

namespace {

const char* kHelp = R"(usage: loom-inspector GRAPH [options]

Opens a window that renders GRAPH live: the graph (click a port to view its texture),
parameter widgets, a texture viewer (exposure, channels, false colour, pixel readout, save),
per-pass GPU timings, camera controls, hot reload of shaders and of GRAPH, JSON save and Lua.

  --scene FILE            scene (.json Loom, .xml Mitsuba, .gltf/.glb, .obj)
  --define NAME=VALUE     Mitsuba scene variable (repeatable)
  --script FILE.lua       run a Lua script at start (output in the Script tab; run it again there)
  --width W, --height H   render size (default 256 x 256)
  --window WxH            window size (default 1280x800)
  --seed K                random seed (default 0)
  --view PASS.PORT        port shown in the texture viewer first (default: first graph output)
  --select PASS           pass whose parameters show first (default: the first pass)
  --frames N              render N frames, then exit (prints frame times)
  --screenshot FILE.png   with --frames: write the whole window to FILE before exiting
  --device D              device index or name (default: LOOM_DEVICE, else lavapipe)
  --validation            enable Vulkan validation layers

LOOM_GPU_TIMEOUT=S (default 600, 0 = forever): a frame still running after S seconds ends the
inspector with code 2, naming the pass (a shader that never terminates, e.g. after hot reload).

Keys: Space pause, N single step, R reset accumulation, Esc quit.
Without a display, run under a virtual one: xvfb-run -a loom-inspector ...
)";

using cli::parseUint;
using cli::UsageError;

inspector::InspectorApp::Options parseArgs(const std::vector<std::string>& args) {
    inspector::InspectorApp::Options o;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto value = [&]() -> const std::string& {
            if (i + 1 >= args.size()) throw UsageError(a + " expects a value");
            return args[++i];
        };
        if (a == "--scene") {
            o.scene = value();
        } else if (a == "--define" || a == "-D") {
            std::string d = value();
            auto eq = d.find('=');
            if (eq == std::string::npos || eq == 0)
                throw UsageError("--define expects NAME=VALUE, got '" + d + "'");
            o.sceneDefines[d.substr(0, eq)] = d.substr(eq + 1);
        } else if (a == "--script") {
            o.script = value();
        } else if (a == "--width") {
            o.width = parseUint(a, value());
        } else if (a == "--height") {
            o.height = parseUint(a, value());
        } else if (a == "--window") {
            std::string v = value();
            auto x = v.find('x');
            if (x == std::string::npos) throw UsageError("--window expects WxH, got '" + v + "'");
            o.windowWidth = int(parseUint(a, v.substr(0, x)));
            o.windowHeight = int(parseUint(a, v.substr(x + 1)));
        } else if (a == "--seed") {
            o.seed = parseUint(a, value());
        } else if (a == "--view") {
            o.view = value();
        } else if (a == "--select") {
            o.select = value();
        } else if (a == "--frames") {
            o.frames = parseUint(a, value());
        } else if (a == "--screenshot") {
            o.screenshot = value();
        } else if (a == "--device") {
            o.device = value();
        } else if (a == "--validation") {
            o.validation = true;
        } else if (!a.empty() && a[0] == '-') {
            throw UsageError("unknown option '" + a + "' (see loom-inspector --help)");
        } else if (o.graph.empty()) {
            o.graph = a;
        } else {
            throw UsageError("more than one graph given ('" + o.graph + "', '" + a + "')");
        }
    }
    if (o.graph.empty()) throw UsageError("no graph given (see loom-inspector --help)");
    if (o.width == 0 || o.height == 0) throw UsageError("--width and --height must be positive");
    if (o.windowWidth < 320 || o.windowHeight < 240)
        throw UsageError("--window must be at least 320x240");
    if (!o.screenshot.empty() && o.frames == 0)
        throw UsageError("--screenshot needs --frames N (frames to render before the shot)");
    return o;
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<std::string> args(argv + 1, argv + argc);
    for (const auto& a : args)
        if (a == "--help" || a == "-h") {
            std::fputs(kHelp, stdout);
            return 0;
        }
    try {
        cli::setGpuTimeout(cli::defaultGpuTimeout(), "loom-inspector: ");
        inspector::InspectorApp app(parseArgs(args));
        return app.run();
    } catch (const UserError& e) {
        std::fprintf(stderr, "loom-inspector: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "loom-inspector: internal error: %s\n", e.what());
        return 1;
    }
}
