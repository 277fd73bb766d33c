#pragma once
// Parameter widgets derived from a pass's declaration (ParamDesc): which widget, its range,
// choices and tooltip. Window-free so the mapping is unit-tested; the inspector draws them with
// Dear ImGui (InspectorApp.cpp) and applies edits through the graph's own validation.
#include <optional>
#include <string>
#include <vector>

#include "core/graph/RenderGraph.h"

namespace loom::inspector {

enum class WidgetKind {
    Checkbox,     // Bool
    SliderInt,    // Int with a finite range
    DragInt,      // Int with an open range
    SliderFloat,  // Float with a finite range
    DragFloat,    // Float with an open range
    Combo,        // Enum
    Vector,       // Vec2/3/4: one drag per component, clamped to the range
    Text,         // String
    JsonText      // Json: edited as JSON text
};
const char* widgetKindName(WidgetKind k);

struct ParamWidget {
    std::string name;
    std::string tooltip;  // doc, default and range
    WidgetKind kind = WidgetKind::DragFloat;
    std::optional<double> min, max;
    bool logarithmic = false;          // float sliders spanning decades (min > 0, max/min >= 1000)
    float dragSpeed = 0.01f;           // drags: about 1/100 of the typical magnitude
    int components = 1;                // Vector
    std::vector<std::string> choices;  // Combo
    json defaultValue;
};

ParamWidget paramWidget(const ParamDesc& desc);
std::vector<ParamWidget> paramWidgets(const PassReflection& reflection);

// Sets PASS.PARAM through the graph (the same validation as JSON, Lua and --set). Returns ""
// on success or the error message; the graph is unchanged on error.
std::string applyParam(RenderGraph& graph, const std::string& pass, const std::string& param,
                       const json& value);
// Parses the text of a JsonText widget; returns "" or the parse error.
std::string parseJsonText(const std::string& text, json& value);

}  // namespace loom::inspector
