#include "apps/inspector/InspectorApp.h"

#include <GLFW/glfw3.h>

#include <unistd.h>
#include <algorithm>
#include <cfloat>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "apps/inspector/MemoryTable.h"
#include "apps/inspector/ParamWidgets.h"
#include "core/scene/Camera.h"
#include "core/scene/SceneGpu.h"
#include "core/script/LuaBindings.h"
#include "core/util/Log.h"
#include "imgui.h"
#include "imgui_stdlib.h"

namespace loom::inspector {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

constexpr size_t kHistory = 240;  // frame-time history length
const ImU32 kNodeBody = IM_COL32(48, 52, 62, 255);
const ImU32 kNodeHeader = IM_COL32(70, 96, 150, 255);
const ImU32 kNodeHeaderSelected = IM_COL32(214, 130, 40, 255);
const ImU32 kNodeHeaderCulled = IM_COL32(80, 80, 80, 255);
const ImU32 kEdge = IM_COL32(200, 200, 210, 255);
const ImU32 kEdgeViewed = IM_COL32(255, 190, 60, 255);
const ImU32 kPinTexture = IM_COL32(110, 200, 120, 255);
const ImU32 kPinBuffer = IM_COL32(120, 160, 230, 255);
const ImU32 kOutputMark = IM_COL32(240, 90, 90, 255);

ImVec4 severityColour(int s) {
    return s == 2   ? ImVec4(1.0f, 0.45f, 0.4f, 1.0f)
           : s == 1 ? ImVec4(1.0f, 0.8f, 0.3f, 1.0f)
                    : ImVec4(0.8f, 0.8f, 0.8f, 1.0f);
}

std::string readText(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::string luaQuote(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
        if (c == '\\' || c == '"') out += '\\';
        if (c == '\n') {
            out += "\\n";
            continue;
        }
        out += c;
    }
    return out + "\"";
}

}  // namespace

InspectorApp::InspectorApp(Options options) : mOptions(std::move(options)) {
    // Parse the graph before opening anything: bad input fails fast with the file's message.
    auto graph = RenderGraph::load(mOptions.graph);
    graph->setAliasing(false);  // every intermediate stays readable for the texture viewer

    Presenter::Options po;
    po.width = mOptions.windowWidth;
    po.height = mOptions.windowHeight;
    po.title = "loom-inspector - " + mOptions.graph;
    mPresenter = std::make_unique<Presenter>(po);

    gpu::Context::Options go;
    go.device = mOptions.device;
    go.validation = mOptions.validation;
    go.instanceExtensions = Presenter::instanceExtensions();
    go.deviceExtensions = Presenter::deviceExtensions();
    go.queueFamilyFilter = &Presenter::presentationSupport;
    auto gpu = gpu::Context::create(go);
    mGpu = gpu;
    mPresenter->attach(gpu);

    mRenderer = std::make_unique<Renderer>(gpu, std::move(graph), mOptions.width, mOptions.height,
                                           mOptions.seed);
    mRenderer->shaders().setKeepLastGood(true);
    if (!mOptions.scene.empty()) {
        mRenderer->loadScene(mOptions.scene, mOptions.sceneDefines);
        mSceneCamera = mRenderer->scene()->cpu().camera;
        resetCamera();
    }
    mGraphWatcher = FileWatcher(mOptions.graph);
    mGraphSavePath = mOptions.graph;
    mScriptPath = mOptions.script;
    mLayout = layoutGraph(mRenderer->graph());
    mSelectedPass = mOptions.select;
    if (mSelectedPass.empty() && !mRenderer->graph().passes().empty())
        mSelectedPass = mRenderer->graph().passes().front()->name();
    mViewPort = mOptions.view;
    if (mViewPort.empty() && !mRenderer->graph().outputs().empty())
        mViewPort = mRenderer->graph().outputs().front();
    log(Severity::Info,
        fmt::format("device: {} ({})", gpu->deviceInfo().name, gpu->deviceInfo().type));
}

InspectorApp::~InspectorApp() {
    // The display image belongs to the device; release it before the renderer and window.
    mDisplay.image.reset();
}

void InspectorApp::log(Severity s, const std::string& text) {
    mMessages.push_back({s, text});
    if (mMessages.size() > 500) mMessages.erase(mMessages.begin());
    if (s == Severity::Error) {
        mLastError = text;
        logMessage(LogLevel::Error, text);
    } else {
        logMessage(s == Severity::Warning ? LogLevel::Warning : LogLevel::Info, text);
    }
}

void InspectorApp::resetCamera() {
    if (!mSceneCamera) return;
    mCamera.reset(scene::cameraAt(*mSceneCamera, mRenderer->time()),
                  mRenderer->scene()->boundingSphere());
    mRenderer->scene()->setCamera(*mSceneCamera);
    mCameraMoved = false;
}

void InspectorApp::renderFrame() {
    auto t0 = Clock::now();
    try {
        if (mPlayPath) mRenderer->setTime(mRenderer->time() + 1.0f);
        mRenderer->frame();
        mFrameFailed = false;
        mNewFrame = true;
        ++mFramesDone;
    } catch (const std::exception& e) {
        // Shown in the UI; rendering pauses until something changes (no error storm).
        log(Severity::Error, e.what());
        mFrameFailed = true;
        return;
    }
    for (const auto& err : mRenderer->shaders().takeErrors())
        log(Severity::Error, err + "\n(the last good version keeps running)");
    mLastFrameMs = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    mFrameMs.push_back(float(mLastFrameMs));
    mGpuMs.push_back(float(mRenderer->graph().frameGpuMs()));
    while (mFrameMs.size() > kHistory) mFrameMs.pop_front();
    while (mGpuMs.size() > kHistory) mGpuMs.pop_front();
    mViewDirty = true;
}

void InspectorApp::setGraph(std::unique_ptr<RenderGraph> graph, const std::string& why) {
    graph->setAliasing(false);
    auto old = mRenderer->setGraph(std::move(graph));
    try {
        mRenderer->frame();
    } catch (const std::exception& e) {
        // Keep the last good graph running.
        mRenderer->setGraph(std::move(old));
        log(Severity::Error, std::string(e.what()) + "\n(the last good graph keeps running)");
        return;
    }
    log(Severity::Info, why);
    mLayout = layoutGraph(mRenderer->graph());
    mTextEdits.clear();
    if (!mRenderer->graph().findPass(mSelectedPass) && !mRenderer->graph().passes().empty())
        mSelectedPass = mRenderer->graph().passes().front()->name();
    mFrameFailed = false;
    mViewDirty = true;
}

void InspectorApp::pollHotReload() {
    auto now = Clock::now();
    if (now - mLastPoll < std::chrono::milliseconds(500)) return;
    mLastPoll = now;
    try {
        size_t n = mRenderer->graph().reloadShaders(mRenderer->shaders());
        if (n) {
            log(Severity::Info, fmt::format("{} shader(s) changed on disk: recompiling", n));
            mFrameFailed = false;  // try again with the new sources
        }
    } catch (const std::exception& e) {
        log(Severity::Error, e.what());
    }
    if (mGraphWatcher.changed()) {
        try {
            setGraph(RenderGraph::load(mOptions.graph), "graph reloaded from " + mOptions.graph);
        } catch (const std::exception& e) {
            log(Severity::Error, std::string(e.what()) + "\n(the last good graph keeps running)");
        }
    }
}

void InspectorApp::refreshView() {
    if (!mViewDirty) return;
    mViewDirty = false;
    const RenderGraph& g = mRenderer->graph();
    auto tex = g.outputTexture(mViewPort);
    if (!tex) {
        if (mViewPort.empty())
            mViewStatus = "click a port in the graph to view it";
        else if (g.outputBuffer(mViewPort))
            mViewStatus = mViewPort + " is a buffer (" +
                          std::to_string(g.outputBuffer(mViewPort)->size()) + " bytes)";
        else
            mViewStatus = mViewPort +
                          " has no resource (culled pass, unused optional port, or "
                          "no frame rendered yet)";
        return;
    }
    try {
        mViewImage = downloadImage(mRenderer->gpu(), *tex);
        auto rgba = toDisplay(mViewImage, mViewSettings);
        mPresenter->updateTexture(mDisplay, mViewImage.width, mViewImage.height, rgba.data());
        mViewStatus.clear();
    } catch (const std::exception& e) {
        mViewStatus = e.what();
    }
}

void InspectorApp::runScript() {
    if (mScriptPath.empty()) return;
    std::string outFile =
        (fs::temp_directory_path() / ("loom-inspector-lua-" + std::to_string(::getpid()) + ".txt"))
            .string();
    mScriptOutput.clear();
    try {
        script::LuaRuntime::Options lo;
        lo.gpu = mGpu;
        std::stringstream ss(mScriptArgs);
        for (std::string a; ss >> a;) lo.args.push_back(a);
        // Scripts may name the inspector's graph and scene: loom.arg("graph"), loom.arg("scene").
        lo.args.push_back("graph=" + mOptions.graph);
        if (!mOptions.scene.empty()) lo.args.push_back("scene=" + mOptions.scene);
        lo.printErrors = false;
        script::LuaRuntime lua(lo);
        // print() goes to a file the panel shows (stdout is the terminal's).
        lua.runString("local f = assert(io.open(" + luaQuote(outFile) +
                          ", 'w'))\n"
                          "print = function(...)\n"
                          "  local t = table.pack(...)\n"
                          "  for i = 1, t.n do t[i] = tostring(t[i]) end\n"
                          "  f:write(table.concat(t, '\\t', 1, t.n), '\\n'); f:flush()\n"
                          "end\n",
                      "=inspector");
        auto t0 = Clock::now();
        int rc = lua.runFile(mScriptPath);
        double s = std::chrono::duration<double>(Clock::now() - t0).count();
        mScriptOutput = readText(outFile);
        if (rc != 0) mScriptOutput += "\n" + lua.lastError();
        mScriptOutput += fmt::format("\n[{} exited {} after {:.2f} s]", mScriptPath, rc, s);
        log(rc ? Severity::Error : Severity::Info,
            fmt::format("script {} exited {}", mScriptPath, rc) +
                (rc ? ": " + lua.lastError() : "") +
                (mScriptOutput.empty() ? "" : "; output:\n" + readText(outFile)));
    } catch (const std::exception& e) {
        mScriptOutput += std::string("\n") + e.what();
        log(Severity::Error, e.what());
    }
    std::error_code ec;
    fs::remove(outFile, ec);
}

// ---------------------------------------------------------------------------------------------
// Main loop

int InspectorApp::run() {
    if (!mScriptPath.empty()) runScript();  // --script: run once at start, output in the panel
    const bool screenshot = !mOptions.screenshot.empty();
    // With --frames the UI runs two frames more than the graph so every panel shows the last
    // graph frame (Dear ImGui lays some widgets out one frame late).
    const uint64_t uiFrames = mOptions.frames ? mOptions.frames + 2 : 0;
    uint64_t uiFrame = 0;
    mPresenter->setMouseEnabled(mOptions.frames == 0);
    bool anyFailure = false;
    auto start = Clock::now();
    while (!mPresenter->shouldClose()) {
        mPresenter->newFrame();
        pollHotReload();
        bool wantFrame = (!mPaused || mStep) && !mFrameFailed;
        if (mOptions.frames) wantFrame = mFramesDone < mOptions.frames && !mFrameFailed;
        if (wantFrame) renderFrame();
        anyFailure = anyFailure || mFrameFailed;
        mStep = false;
        refreshView();
        drawUi();
        ++uiFrame;
        const bool last = uiFrames && uiFrame >= uiFrames;
        if (last && screenshot) {
            ImageData shot;
            mPresenter->render(&shot);
            try {
                if (auto dir = fs::path(mOptions.screenshot).parent_path(); !dir.empty())
                    fs::create_directories(dir);
                writeImage(mOptions.screenshot, shot);
            } catch (const std::exception& e) {
                logMessage(LogLevel::Error, e.what());
                return 2;
            }
            std::printf("loom-inspector: wrote %s (%ux%u)\n", mOptions.screenshot.c_str(),
                        shot.width, shot.height);
        } else {
            mPresenter->render();
        }
        if (last) break;
    }
    if (mOptions.frames) {
        double wall = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
        double frameSum = 0.0, gpuSum = 0.0;
        for (float f : mFrameMs) frameSum += f;
        for (float f : mGpuMs) gpuSum += f;
        size_t n = std::max<size_t>(mFrameMs.size(), 1);
        std::printf(
            "loom-inspector: %llu graph frames at %ux%u: %.1f ms per graph frame (GPU %.1f ms), "
            "%.1f ms per window frame\n",
            (unsigned long long)mFramesDone, mOptions.width, mOptions.height, frameSum / n,
            gpuSum / n, wall / double(std::max<uint64_t>(uiFrame, 1)));
    }
    if (anyFailure && !mLastError.empty()) {
        std::fprintf(stderr, "loom-inspector: %s\n", mLastError.c_str());
        return 2;
    }
    return 0;
}

// ---------------------------------------------------------------------------------------------
// UI

void InspectorApp::drawUi() {
    drawMenuBar();
    // A fixed tiling that follows the window size: graph | parameters over texture | tabs.
    const ImGuiViewport* vp = ImGui::GetMainViewport();
    const float top = ImGui::GetFrameHeight();  // menu bar
    const ImVec2 size(vp->WorkSize.x, vp->Size.y - top);
    const float leftW = std::floor(size.x * 0.58f);
    const float topH = std::floor(size.y * 0.45f);
    const ImGuiWindowFlags fixed =
        ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse;
    auto place = [&](float x, float y, float w, float h) {
        ImGui::SetNextWindowPos(ImVec2(vp->Pos.x + x, vp->Pos.y + top + y), ImGuiCond_Always);
        ImGui::SetNextWindowSize(ImVec2(w, h), ImGuiCond_Always);
    };

    place(0, 0, leftW, topH);
    if (ImGui::Begin("Graph", nullptr, fixed | ImGuiWindowFlags_NoScrollbar)) drawGraphView();
    ImGui::End();
    place(leftW, 0, size.x - leftW, topH);
    if (ImGui::Begin("Parameters", nullptr, fixed)) drawParameters();
    ImGui::End();
    place(0, topH, leftW, size.y - topH);
    if (ImGui::Begin("Texture", nullptr,
                     fixed | ImGuiWindowFlags_NoScrollbar | ImGuiWindowFlags_NoScrollWithMouse))
        drawTextureViewer();
    ImGui::End();
    place(leftW, topH, size.x - leftW, size.y - topH);
    if (ImGui::Begin("Frame", nullptr, fixed)) {
        if (ImGui::BeginTabBar("tabs")) {
            if (ImGui::BeginTabItem("Timings")) {
                drawTimings();
                ImGui::EndTabItem();
            }
            if (ImGui::BeginTabItem("Memory")) {
                drawMemory();
                ImGui::EndTabItem();
            }
            if (ImGui::BeginTabItem("Camera")) {
                drawCamera();
                ImGui::EndTabItem();
            }
            if (ImGui::BeginTabItem("Script")) {
                drawScript();
                ImGui::EndTabItem();
            }
            if (ImGui::BeginTabItem("Log")) {
                drawLog();
                ImGui::EndTabItem();
            }
            ImGui::EndTabBar();
        }
    }
    ImGui::End();
}

void InspectorApp::drawMenuBar() {
    if (!ImGui::BeginMainMenuBar()) return;
    if (ImGui::BeginMenu("File")) {
        if (ImGui::MenuItem("Save graph", "Ctrl+S")) {
            std::string err = saveGraphChecked(mRenderer->graph(), mGraphSavePath);
            if (err.empty()) {
                log(Severity::Info, "saved " + mGraphSavePath);
                if (mGraphSavePath == mOptions.graph) mGraphWatcher = FileWatcher(mOptions.graph);
            } else {
                log(Severity::Error, err);
            }
        }
        ImGui::SetNextItemWidth(320);
        ImGui::InputText("save as", &mGraphSavePath);
        ImGui::Separator();
        if (ImGui::MenuItem("Reload graph from disk")) try {
                setGraph(RenderGraph::load(mOptions.graph), "graph reloaded");
            } catch (const std::exception& e) {
                log(Severity::Error, e.what());
            }
        if (ImGui::MenuItem("Quit", "Esc")) glfwSetWindowShouldClose(mPresenter->window(), 1);
        ImGui::EndMenu();
    }
    if (ImGui::BeginMenu("Render")) {
        ImGui::MenuItem("Pause", "Space", &mPaused);
        if (ImGui::MenuItem("Single step", "N")) mStep = true;
        if (ImGui::MenuItem("Reset accumulation", "R")) mRenderer->reset();
        ImGui::EndMenu();
    }
    // Keyboard shortcuts (not while typing into a field).
    if (!ImGui::GetIO().WantTextInput) {
        if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Space))) mPaused = !mPaused;
        if (ImGui::IsKeyPressed('N')) mStep = true;
        if (ImGui::IsKeyPressed('R')) mRenderer->reset();
        if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape)))
            glfwSetWindowShouldClose(mPresenter->window(), 1);
    }
    ImGui::Separator();
    ImGui::Text("%s  %ux%u  frame %llu  %.1f ms%s", mRenderer->graph().name().c_str(),
                mRenderer->width(), mRenderer->height(),
                (unsigned long long)mRenderer->graph().frameIndex(), mLastFrameMs,
                mPaused ? "  [paused]" : "");
    if (!mLastError.empty()) {
        ImGui::Separator();
        std::string first = mLastError.substr(0, mLastError.find('\n'));
        ImGui::TextColored(severityColour(2), "%s", first.c_str());
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", mLastError.c_str());
        if (ImGui::SmallButton("dismiss")) mLastError.clear();
    }
    ImGui::EndMainMenuBar();
}

void InspectorApp::drawGraphView() {
    const RenderGraph& g = mRenderer->graph();
    std::set<std::string> culled;
    if (const auto* cg = g.compiled()) culled.insert(cg->culled.begin(), cg->culled.end());

    ImGui::BeginChild("canvas", ImVec2(0, 0), false, ImGuiWindowFlags_HorizontalScrollbar);
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const ImVec2 origin = ImGui::GetCursorScreenPos();
    ImGui::InvisibleButton("graph",
                           ImVec2(std::max(mLayout.width, 1.0f), std::max(mLayout.height, 1.0f)));
    const bool clicked = ImGui::IsItemClicked(ImGuiMouseButton_Left);
    const bool hovered = ImGui::IsItemHovered();
    // Right-drag pans the canvas.
    if (hovered && ImGui::IsMouseDragging(ImGuiMouseButton_Right)) {
        ImVec2 d = ImGui::GetIO().MouseDelta;
        ImGui::SetScrollX(ImGui::GetScrollX() - d.x);
        ImGui::SetScrollY(ImGui::GetScrollY() - d.y);
    }
    const ImVec2 mouse = ImGui::GetIO().MousePos;
    auto at = [&](float x, float y) { return ImVec2(origin.x + x, origin.y + y); };
    const float pinR = 5.0f;

    // Edges under the boxes: cubic curves from output pin to input pin.
    for (const auto& e : mLayout.edges) {
        const auto& s = mLayout.nodes[e.src];
        const auto& d = mLayout.nodes[e.dst];
        ImVec2 p0, p1;
        bool viewed = false;
        if (e.srcPin >= 0 && e.dstPin >= 0) {
            const auto& sp = s.outputs[e.srcPin];
            const auto& dp = d.inputs[e.dstPin];
            p0 = at(sp.x, sp.y);
            p1 = at(dp.x, dp.y);
            viewed = mViewPort == s.pass + "." + sp.port || mViewPort == d.pass + "." + dp.port;
        } else {
            p0 = at(s.x + s.width, s.y + s.height * 0.5f);
            p1 = at(d.x, d.y + d.height * 0.5f);
        }
        float bend = std::max(40.0f, std::abs(p1.x - p0.x) * 0.5f);
        ImU32 colour = viewed ? kEdgeViewed : e.srcPin < 0 ? IM_COL32(140, 140, 150, 200) : kEdge;
        dl->AddBezierCubic(p0, ImVec2(p0.x + bend, p0.y), ImVec2(p1.x - bend, p1.y), p1, colour,
                           viewed ? 3.0f : 2.0f);
    }

    std::string hoverText;
    for (const auto& node : mLayout.nodes) {
        const bool selected = node.pass == mSelectedPass;
        const bool isCulled = culled.count(node.pass) > 0;
        ImVec2 a = at(node.x, node.y), b = at(node.x + node.width, node.y + node.height);
        dl->AddRectFilled(a, b, kNodeBody, 4.0f);
        dl->AddRectFilled(a, ImVec2(b.x, a.y + 20.0f),
                          selected   ? kNodeHeaderSelected
                          : isCulled ? kNodeHeaderCulled
                                     : kNodeHeader,
                          4.0f, ImDrawFlags_RoundCornersTop);
        dl->AddRect(a, b, selected ? kNodeHeaderSelected : IM_COL32(90, 95, 110, 255), 4.0f, 0,
                    selected ? 2.0f : 1.0f);
        std::string title = node.pass + " : " + node.type;
        dl->PushClipRect(a, ImVec2(b.x - 2, b.y), true);
        dl->AddText(ImVec2(a.x + 6, a.y + 3), IM_COL32_WHITE, title.c_str());
        dl->PopClipRect();
        if (ImGui::IsMouseHoveringRect(a, b) && hovered)
            hoverText = node.pass + " (" + node.type + ")" + (isCulled ? " - culled" : "");

        auto drawPin = [&](const LayoutPin& pin) {
            ImVec2 c = at(pin.x, pin.y);
            std::string key = node.pass + "." + pin.port;
            ImU32 colour = pin.kind == ResourceKind::Texture ? kPinTexture : kPinBuffer;
            if (mViewPort == key) dl->AddCircleFilled(c, pinR + 3.0f, kEdgeViewed);
            if (pin.optional)
                dl->AddCircle(c, pinR, colour, 12, 2.0f);
            else
                dl->AddCircleFilled(c, pinR, colour);
            ImVec2 ts = ImGui::CalcTextSize(pin.port.c_str());
            float tx = pin.isInput ? c.x + pinR + 4.0f : c.x - pinR - 4.0f - ts.x;
            dl->AddText(ImVec2(tx, c.y - ts.y * 0.5f), IM_COL32(220, 220, 220, 255),
                        pin.port.c_str());
            if (pin.graphOutput) {  // a flag past the right edge: "this is a graph output"
                ImVec2 f(c.x + pinR + 3.0f, c.y);
                dl->AddTriangleFilled(ImVec2(f.x, f.y - 6), ImVec2(f.x, f.y + 6),
                                      ImVec2(f.x + 10, f.y), kOutputMark);
            }
            float dx = mouse.x - c.x, dy = mouse.y - c.y;
            if (hovered && dx * dx + dy * dy <= (pinR + 4) * (pinR + 4)) {
                hoverText = key + (pin.graphOutput ? "  [graph output]" : "");
                if (const auto* cg = g.compiled()) {
                    auto it = cg->portResource.find(key);
                    if (it != cg->portResource.end()) {
                        const auto& r = cg->resources[it->second];
                        hoverText += r.kind == ResourceKind::Texture
                                         ? fmt::format("\n{} {}x{} ({})", gpu::formatName(r.format),
                                                       r.width, r.height, r.name)
                                         : fmt::format("\nbuffer {} bytes ({})", r.bytes, r.name);
                    }
                }
                hoverText += "\nclick to view";
                if (clicked) {
                    mViewPort = key;
                    mSelectedPass = node.pass;
                    mViewDirty = true;
                }
            }
        };
        for (const auto& pin : node.inputs) drawPin(pin);
        for (const auto& pin : node.outputs) drawPin(pin);
        if (clicked && ImGui::IsMouseHoveringRect(a, b)) mSelectedPass = node.pass;
    }
    if (!hoverText.empty()) ImGui::SetTooltip("%s", hoverText.c_str());
    ImGui::EndChild();
}

void InspectorApp::drawParameters() {
    RenderGraph& g = mRenderer->graph();
    // Pass list on top: any pass can be selected here too.
    ImGui::SetNextItemWidth(-1);
    if (ImGui::BeginCombo("##pass", mSelectedPass.c_str())) {
        for (const auto& p : g.passes())
            if (ImGui::Selectable((p->name() + " : " + p->type()).c_str(),
                                  p->name() == mSelectedPass))
                mSelectedPass = p->name();
        ImGui::EndCombo();
    }
    Pass* pass = g.findPass(mSelectedPass);
    if (!pass) {
        ImGui::TextDisabled("select a pass in the graph");
        return;
    }
    if (const auto* info = PassRegistry::instance().find(pass->type()))
        ImGui::TextWrapped("%s", info->doc.c_str());
    ImGui::Separator();

    std::vector<ParamWidget> widgets;
    try {
        widgets = paramWidgets(pass->reflection());
    } catch (const std::exception& e) {
        ImGui::TextColored(severityColour(2), "%s", e.what());
        return;
    }
    if (widgets.empty()) ImGui::TextDisabled("no parameters");
    for (const auto& w : widgets) {
        const std::string key = pass->name() + "." + w.name;
        json value = pass->getParam(w.name);
        std::optional<json> edited;
        ImGui::PushID(key.c_str());
        ImGui::SetNextItemWidth(-ImGui::GetContentRegionAvail().x * 0.38f);
        const char* label = w.name.c_str();
        switch (w.kind) {
            case WidgetKind::Checkbox: {
                bool b = value.is_boolean() && value.get<bool>();
                if (ImGui::Checkbox(label, &b)) edited = b;
                break;
            }
            case WidgetKind::SliderInt:
            case WidgetKind::DragInt: {
                int i = value.is_number() ? value.get<int>() : 0;
                int lo = w.min ? int(std::max<double>(*w.min, INT_MIN)) : INT_MIN;
                int hi = w.max ? int(std::min<double>(*w.max, INT_MAX)) : INT_MAX;
                bool changed = w.kind == WidgetKind::SliderInt
                                   ? ImGui::SliderInt(label, &i, lo, hi)
                                   : ImGui::DragInt(label, &i, w.dragSpeed, lo, hi);
                if (changed) edited = std::clamp(i, lo, hi);
                break;
            }
            case WidgetKind::SliderFloat:
            case WidgetKind::DragFloat: {
                float f = value.is_number() ? value.get<float>() : 0.0f;
                float lo = w.min ? float(*w.min) : -FLT_MAX, hi = w.max ? float(*w.max) : FLT_MAX;
                bool changed =
                    w.kind == WidgetKind::SliderFloat
                        ? ImGui::SliderFloat(label, &f, lo, hi, "%.4g",
                                             w.logarithmic ? ImGuiSliderFlags_Logarithmic : 0)
                        : ImGui::DragFloat(label, &f, w.dragSpeed, lo, hi, "%.4g");
                if (changed) edited = double(std::clamp(f, lo, hi));
                break;
            }
            case WidgetKind::Combo: {
                std::string cur = value.is_string() ? value.get<std::string>() : "";
                if (ImGui::BeginCombo(label, cur.c_str())) {
                    for (const auto& c : w.choices)
                        if (ImGui::Selectable(c.c_str(), c == cur)) edited = c;
                    ImGui::EndCombo();
                }
                break;
            }
            case WidgetKind::Vector: {
                float v[4] = {0, 0, 0, 0};
                for (int c = 0; c < w.components && value.is_array() && c < int(value.size()); ++c)
                    v[c] = value[c].get<float>();
                float lo = w.min ? float(*w.min) : -FLT_MAX, hi = w.max ? float(*w.max) : FLT_MAX;
                if (ImGui::DragScalarN(label, ImGuiDataType_Float, v, w.components, w.dragSpeed,
                                       &lo, &hi, "%.4g")) {
                    json arr = json::array();
                    for (int c = 0; c < w.components; ++c) arr.push_back(double(v[c]));
                    edited = arr;
                }
                break;
            }
            case WidgetKind::Text: {
                auto it = mTextEdits
                              .try_emplace(
                                  key, value.is_string() ? value.get<std::string>() : value.dump())
                              .first;
                // Applied on Enter: a half-typed shader path is not an error.
                if (ImGui::InputText(label, &it->second, ImGuiInputTextFlags_EnterReturnsTrue))
                    edited = it->second;
                break;
            }
            case WidgetKind::JsonText: {
                auto it = mTextEdits.try_emplace(key, value.dump(2)).first;
                ImGui::TextUnformatted(label);
                ImGui::InputTextMultiline("##json", &it->second,
                                          ImVec2(-1, ImGui::GetTextLineHeight() * 6));
                if (ImGui::SmallButton("apply")) {
                    json parsed;
                    std::string err = parseJsonText(it->second, parsed);
                    if (err.empty())
                        edited = parsed;
                    else
                        log(Severity::Error, key + ": " + err);
                }
                ImGui::SameLine();
                if (ImGui::SmallButton("revert")) it->second = value.dump(2);
                break;
            }
        }
        if (ImGui::IsItemHovered() && !w.tooltip.empty())
            ImGui::SetTooltip("%s", w.tooltip.c_str());
        if (edited) {
            // The graph validates (range, type, files); an error leaves the value unchanged.
            std::string err = applyParam(g, pass->name(), w.name, *edited);
            if (err.empty()) {
                mFrameFailed = false;  // render the edit immediately, paused or not
                mStep = mPaused;
                if (w.kind == WidgetKind::Text || w.kind == WidgetKind::JsonText)
                    mTextEdits.erase(key);
                // Ports may have changed (ComputePass definitions): lay out again.
                mLayout = layoutGraph(g);
            } else {
                log(Severity::Error, err);
            }
        }
        ImGui::PopID();
    }
    ImGui::Separator();
    if (ImGui::Button("Reset to defaults")) {
        for (const auto& w : widgets) {
            std::string err = applyParam(g, pass->name(), w.name, w.defaultValue);
            if (!err.empty()) log(Severity::Error, err);
        }
        mTextEdits.clear();
        mFrameFailed = false;
    }
    // Pass statistics (error metrics, counters) when the pass exposes any.
    auto stats = pass->stats();
    for (const auto& [k, v] : stats) ImGui::Text("%s = %.6g", k.c_str(), v);
}

void InspectorApp::drawTextureViewer() {
    const RenderGraph& g = mRenderer->graph();
    // Toolbar: port, exposure, channel, mode, zoom, save.
    ImGui::SetNextItemWidth(150);
    if (ImGui::BeginCombo("##port", mViewPort.empty() ? "(port)" : mViewPort.c_str())) {
        for (const auto& node : mLayout.nodes)
            for (const auto* pins : {&node.outputs, &node.inputs})
                for (const auto& pin : *pins) {
                    std::string key = node.pass + "." + pin.port;
                    if (ImGui::Selectable(key.c_str(), key == mViewPort)) {
                        mViewPort = key;
                        mViewDirty = true;
                    }
                }
        ImGui::EndCombo();
    }
    bool changed = false;
    ImGui::SameLine();
    ImGui::SetNextItemWidth(90);
    changed |= ImGui::SliderFloat("EV", &mViewSettings.exposure, -10.0f, 10.0f, "%.1f");
    ImGui::SameLine();
    ImGui::SetNextItemWidth(90);
    int channel = int(mViewSettings.channel);
    if (ImGui::Combo("##channel", &channel, "RGB\0R\0G\0B\0A\0Luminance\0")) {
        mViewSettings.channel = Channel(channel);
        changed = true;
    }
    ImGui::SameLine();
    ImGui::SetNextItemWidth(140);
    int mode = int(mViewSettings.mode);
    if (ImGui::Combo("##mode", &mode, "Colour\0Signed (false colour)\0Error (false colour)\0")) {
        mViewSettings.mode = ColorMode(mode);
        changed = true;
    }
    if (mViewSettings.mode != ColorMode::Color) {
        ImGui::SameLine();
        ImGui::SetNextItemWidth(90);
        changed |= ImGui::DragFloat("range", &mViewSettings.range, 0.01f, 1e-6f, 1e6f, "%.3g",
                                    ImGuiSliderFlags_Logarithmic);
        if (mViewSettings.mode == ColorMode::Error) {
            ImGui::SameLine();
            changed |= ImGui::Checkbox("log", &mViewSettings.logScale);
        }
    }
    if (changed) mViewDirty = true;
    ImGui::SameLine();
    if (ImGui::Button(mFit ? "1:1" : "Fit")) {
        mFit = !mFit;
        mZoom = 1.0f;
        mPan = ImVec2(0, 0);
    }
    ImGui::SameLine();
    ImGui::Checkbox("camera", &mNavigateCamera);
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "mouse over the image moves the camera:\n"
            "orbit: left-drag orbits, right-drag pans, wheel dollies\n"
            "fly: left-drag looks, WASD/QE move");

    ImGui::SetNextItemWidth(220);
    ImGui::InputText("##save", &mSavePath);
    ImGui::SameLine();
    if (ImGui::Button("Save EXR/PNG") && !mViewImage.pixels.empty()) {
        try {
            if (auto dir = fs::path(mSavePath).parent_path(); !dir.empty())
                fs::create_directories(dir);
            saveView(mSavePath, mViewImage, mViewSettings);
            log(Severity::Info, "saved " + mViewPort + " to " + mSavePath);
        } catch (const std::exception& e) {
            log(Severity::Error, e.what());
        }
    }

    // Readout line reserved at the bottom; the image fills the rest.
    const float readoutH = ImGui::GetTextLineHeightWithSpacing();
    ImVec2 avail = ImGui::GetContentRegionAvail();
    avail.y -= readoutH;
    ImVec2 p0 = ImGui::GetCursorScreenPos();
    ImGui::InvisibleButton("image", ImVec2(std::max(avail.x, 1.0f), std::max(avail.y, 1.0f)),
                           ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight);
    const bool hovered = ImGui::IsItemHovered();
    ImDrawList* dl = ImGui::GetWindowDrawList();
    dl->AddRectFilled(p0, ImVec2(p0.x + avail.x, p0.y + avail.y), IM_COL32(25, 25, 28, 255));
    std::string readout;
    if (!mViewStatus.empty() || !mDisplay.image) {
        dl->AddText(ImVec2(p0.x + 8, p0.y + 8), IM_COL32(200, 200, 200, 255),
                    mViewStatus.empty() ? "no texture" : mViewStatus.c_str());
    } else {
        const float w = float(mDisplay.width()), h = float(mDisplay.height());
        float scale = mFit ? std::min(avail.x / w, avail.y / h) : mZoom;
        if (hovered && !mNavigateCamera) {
            ImGuiIO& io = ImGui::GetIO();
            if (io.MouseWheel != 0.0f) {
                mFit = false;
                mZoom = std::clamp(scale * std::pow(1.2f, io.MouseWheel), 0.05f, 64.0f);
            }
            if (ImGui::IsMouseDragging(ImGuiMouseButton_Left)) {
                mPan.x -= io.MouseDelta.x / scale;
                mPan.y -= io.MouseDelta.y / scale;
            }
            scale = mFit ? scale : mZoom;
        }
        ImVec2 centre(p0.x + avail.x * 0.5f, p0.y + avail.y * 0.5f);
        ImVec2 a(centre.x - (w * 0.5f + mPan.x) * scale, centre.y - (h * 0.5f + mPan.y) * scale);
        ImVec2 b(a.x + w * scale, a.y + h * scale);
        dl->PushClipRect(p0, ImVec2(p0.x + avail.x, p0.y + avail.y), true);
        mPresenter->drawTexture(dl, mDisplay, a, b);
        dl->PopClipRect();
        if (hovered) {
            ImVec2 m = ImGui::GetIO().MousePos;
            int px = int(std::floor((m.x - a.x) / scale)),
                py = int(std::floor((m.y - a.y) / scale));
            if (px >= 0 && py >= 0 && px < int(w) && py < int(h))
                readout = pixelReadout(mViewImage, uint32_t(px), uint32_t(py));
        }
    }
    handleCameraInput(hovered && mNavigateCamera);
    const auto* tex = g.compiled() ? g.outputTexture(mViewPort).get() : nullptr;
    ImGui::Text(
        "%s %s  %s", mViewPort.c_str(),
        tex ? fmt::format("{} {}x{}", gpu::formatName(tex->format()), tex->width(), tex->height())
                  .c_str()
            : "",
        readout.c_str());
}

void InspectorApp::handleCameraInput(bool hovered) {
    if (!mSceneCamera || !mRenderer->scene()) return;
    ImGuiIO& io = ImGui::GetIO();
    bool moved = false;
    const float turn = 0.008f;  // radians per pixel
    if (hovered) {
        if (ImGui::IsMouseDragging(ImGuiMouseButton_Left)) {
            if (mFlyMode)
                mCamera.look(-io.MouseDelta.x * turn, -io.MouseDelta.y * turn);
            else
                mCamera.orbit(-io.MouseDelta.x * turn, io.MouseDelta.y * turn);
            moved = true;
        }
        if (ImGui::IsMouseDragging(ImGuiMouseButton_Right)) {
            mCamera.pan(io.MouseDelta.x * 0.002f, io.MouseDelta.y * 0.002f);
            moved = true;
        }
        if (io.MouseWheel != 0.0f) {
            mCamera.dolly(io.MouseWheel);
            moved = true;
        }
        if (mFlyMode && !io.WantTextInput) {
            glm::vec3 m(0.0f);
            auto key = [&](int k) { return ImGui::IsKeyDown(k); };
            m.z += key('W') - key('S');
            m.x += key('D') - key('A');
            m.y += key('E') - key('Q');
            if (m != glm::vec3(0.0f)) {
                mCamera.fly(m * mFlySpeed * io.DeltaTime);
                moved = true;
            }
        }
    }
    if (moved) {
        mPlayPath = false;
        mCameraMoved = true;
        mRenderer->scene()->setCamera(mCamera.camera());  // bumps the revision: accumulation resets
    }
}

void InspectorApp::drawTimings() {
    const auto& timings = mRenderer->graph().timings();
    double total = 0.0, maxMs = 1e-6;
    for (const auto& t : timings) {
        total += t.gpuMs;
        maxMs = std::max(maxMs, t.gpuMs);
    }
    ImGui::Text("GPU %.2f ms per frame, %zu passes", mRenderer->graph().frameGpuMs(),
                timings.size());
    // Per-pass bars.
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const float labelW = 110.0f, rowH = ImGui::GetTextLineHeightWithSpacing();
    for (const auto& t : timings) {
        ImVec2 p = ImGui::GetCursorScreenPos();
        float barW = ImGui::GetContentRegionAvail().x - labelW - 80.0f;
        dl->AddText(p, IM_COL32(220, 220, 220, 255), t.pass.c_str());
        float frac = float(t.gpuMs / maxMs);
        dl->AddRectFilled(ImVec2(p.x + labelW, p.y + 2),
                          ImVec2(p.x + labelW + std::max(1.0f, barW * frac), p.y + rowH - 2),
                          t.pass == mSelectedPass ? kNodeHeaderSelected : kNodeHeader);
        std::string ms = fmt::format("{:.2f} ms", t.gpuMs);
        dl->AddText(ImVec2(p.x + labelW + barW + 6, p.y), IM_COL32(220, 220, 220, 255), ms.c_str());
        ImGui::Dummy(ImVec2(labelW + barW + 80.0f, rowH));
        if (ImGui::IsItemClicked()) mSelectedPass = t.pass;
    }
    ImGui::Separator();
    // Frame-time history (wall time of a graph frame, and its GPU time).
    std::vector<float> frame(mFrameMs.begin(), mFrameMs.end()), gpu(mGpuMs.begin(), mGpuMs.end());
    float hi = 1.0f;
    for (float f : frame) hi = std::max(hi, f);
    std::string label = fmt::format("frame {:.1f} ms", frame.empty() ? 0.0f : frame.back());
    const float plotW = ImGui::GetContentRegionAvail().x;  // PlotLines takes no -1 width
    ImGui::PlotLines("##frame", frame.data(), int(frame.size()), 0, label.c_str(), 0.0f, hi * 1.1f,
                     ImVec2(plotW, 60));
    label = fmt::format("GPU {:.1f} ms", gpu.empty() ? 0.0f : gpu.back());
    ImGui::PlotLines("##gpu", gpu.data(), int(gpu.size()), 0, label.c_str(), 0.0f, hi * 1.1f,
                     ImVec2(plotW, 40));
}

void InspectorApp::drawMemory() {
    const RenderGraph& g = mRenderer->graph();
    MemoryTable t = memoryTable(g.memoryReport(), mSelectedPass, g.aliasing());
    ImGui::TextUnformatted(t.summary.c_str());
    const ImGuiTableFlags flags = ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerV |
                                  ImGuiTableFlags_ScrollY | ImGuiTableFlags_Resizable |
                                  ImGuiTableFlags_SizingFixedFit;
    if (!ImGui::BeginTable("memory", 6, flags)) return;
    ImGui::TableSetupScrollFreeze(0, 1);
    for (const char* h : {"resource", "kind", "format/size", "bytes", "lifetime", "shares"})
        ImGui::TableSetupColumn(h);
    ImGui::TableHeadersRow();
    for (const auto& r : t.rows) {
        ImGui::TableNextRow();
        // The selected pass's resources stand out; clicking a row selects its pass.
        if (r.ofSelectedPass)
            ImGui::TableSetBgColor(ImGuiTableBgTarget_RowBg0, kNodeHeaderSelected & 0x60FFFFFF);
        ImGui::TableNextColumn();
        if (ImGui::Selectable(r.name.c_str(), false, ImGuiSelectableFlags_SpanAllColumns))
            mSelectedPass = r.name.substr(0, r.name.find_first_of(".#"));
        for (const std::string* c : {&r.kind, &r.size, &r.bytes, &r.lifetime, &r.shares}) {
            ImGui::TableNextColumn();
            ImGui::TextUnformatted(c->c_str());
        }
    }
    ImGui::EndTable();
}

void InspectorApp::drawCamera() {
    if (ImGui::Button(mPaused ? "Resume" : "Pause")) mPaused = !mPaused;
    ImGui::SameLine();
    if (ImGui::Button("Step")) mStep = true;
    ImGui::SameLine();
    if (ImGui::Button("Reset accumulation")) mRenderer->reset();
    ImGui::Text("frame %llu, time %.1f", (unsigned long long)mRenderer->graph().frameIndex(),
                mRenderer->time());
    ImGui::Separator();
    if (!mSceneCamera || !mRenderer->scene()) {
        ImGui::TextDisabled("no scene (--scene FILE)");
        return;
    }
    int mode = mFlyMode ? 1 : 0;
    ImGui::RadioButton("orbit", &mode, 0);
    ImGui::SameLine();
    ImGui::RadioButton("fly", &mode, 1);
    mFlyMode = mode == 1;
    ImGui::SameLine();
    ImGui::SetNextItemWidth(100);
    ImGui::DragFloat("fly speed", &mFlySpeed, 0.01f, 0.01f, 10.0f, "%.2f");
    ImGui::TextDisabled("tick 'camera' in the texture view, then drag over the image");
    glm::vec3 o = mCamera.origin(), t = mCamera.target();
    ImGui::Text("eye (%.3g, %.3g, %.3g)  target (%.3g, %.3g, %.3g)", o.x, o.y, o.z, t.x, t.y, t.z);
    if (ImGui::Button("Reset camera")) {
        mPlayPath = false;
        resetCamera();
    }
    const bool hasPath = !mSceneCamera->path.empty();
    ImGui::SameLine();
    ImGui::BeginDisabled(!hasPath);
    if (ImGui::Checkbox("play camera path", &mPlayPath) && mPlayPath) {
        mRenderer->scene()->setCamera(*mSceneCamera);  // the path drives the pose again
        mCameraMoved = false;
    }
    ImGui::EndDisabled();
    if (hasPath) {
        float time = mRenderer->time();
        float end = mSceneCamera->path.back().time;
        ImGui::SetNextItemWidth(-1);
        if (ImGui::SliderFloat("##time", &time, 0.0f, std::max(end, 1.0f), "time %.1f")) {
            mRenderer->setTime(time);
            if (!mCameraMoved)
                mCamera.reset(scene::cameraAt(*mSceneCamera, time),
                              mRenderer->scene()->boundingSphere());
        }
    }
}

void InspectorApp::drawScript() {
    ImGui::SetNextItemWidth(-70);
    ImGui::InputText("script", &mScriptPath);
    ImGui::SetNextItemWidth(-70);
    ImGui::InputText("args", &mScriptArgs);
    if (ImGui::Button("Run")) runScript();
    ImGui::SameLine();
    ImGui::TextDisabled("runs synchronously; loom.arg(\"graph\"), loom.arg(\"scene\") name ours");
    ImGui::BeginChild("output", ImVec2(0, 0), true, ImGuiWindowFlags_HorizontalScrollbar);
    ImGui::TextUnformatted(mScriptOutput.c_str());
    ImGui::EndChild();
}

void InspectorApp::drawLog() {
    if (ImGui::SmallButton("clear")) {
        mMessages.clear();
        mLastError.clear();
    }
    ImGui::BeginChild("log", ImVec2(0, 0), true, ImGuiWindowFlags_HorizontalScrollbar);
    for (const auto& m : mMessages)
        ImGui::TextColored(severityColour(int(m.severity)), "%s", m.text.c_str());
    if (ImGui::GetScrollY() >= ImGui::GetScrollMaxY()) ImGui::SetScrollHereY(1.0f);
    ImGui::EndChild();
}

}  // namespace loom::inspector
