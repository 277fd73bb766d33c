#include "apps/inspector/ParamWidgets.h"

#include <cmath>

namespace loom::inspector {

const char* widgetKindName(WidgetKind k) {
    switch (k) {
        case WidgetKind::Checkbox:
            return "checkbox";
        case WidgetKind::SliderInt:
            return "slider-int";
        case WidgetKind::DragInt:
            return "drag-int";
        case WidgetKind::SliderFloat:
            return "slider-float";
        case WidgetKind::DragFloat:
            return "drag-float";
        case WidgetKind::Combo:
            return "combo";
        case WidgetKind::Vector:
            return "vector";
        case WidgetKind::Text:
            return "text";
        case WidgetKind::JsonText:
            return "json";
    }
    return "?";
}

ParamWidget paramWidget(const ParamDesc& desc) {
    ParamWidget w;
    w.name = desc.name;
    w.min = desc.min;
    w.max = desc.max;
    w.defaultValue = desc.defaultValue;
    w.choices = desc.choices;
    const bool bounded = desc.min && desc.max && std::isfinite(*desc.min) &&
                         std::isfinite(*desc.max) && *desc.max > *desc.min;
    switch (desc.type) {
        case ParamType::Bool:
            w.kind = WidgetKind::Checkbox;
            break;
        case ParamType::Int:
            // Sliders only for ranges a mouse can traverse; drags otherwise.
            w.kind = bounded && *desc.max - *desc.min <= 4096 ? WidgetKind::SliderInt
                                                              : WidgetKind::DragInt;
            w.dragSpeed = 0.2f;
            break;
        case ParamType::Float:
            w.kind = bounded ? WidgetKind::SliderFloat : WidgetKind::DragFloat;
            w.logarithmic = bounded && *desc.min > 0 && *desc.max / *desc.min >= 1000.0;
            break;
        case ParamType::Enum:
            w.kind = WidgetKind::Combo;
            break;
        case ParamType::Vec2:
            w.kind = WidgetKind::Vector;
            w.components = 2;
            break;
        case ParamType::Vec3:
            w.kind = WidgetKind::Vector;
            w.components = 3;
            break;
        case ParamType::Vec4:
            w.kind = WidgetKind::Vector;
            w.components = 4;
            break;
        case ParamType::String:
            w.kind = WidgetKind::Text;
            break;
        case ParamType::Json:
            w.kind = WidgetKind::JsonText;
            break;
    }
    if (w.kind == WidgetKind::DragFloat || w.kind == WidgetKind::Vector) {
        double magnitude = 0.0;
        if (desc.defaultValue.is_number()) magnitude = std::abs(desc.defaultValue.get<double>());
        if (desc.defaultValue.is_array())
            for (const auto& c : desc.defaultValue)
                if (c.is_number()) magnitude = std::max(magnitude, std::abs(c.get<double>()));
        w.dragSpeed = float(std::max(magnitude, 1.0) * 0.01);
    }

    // Tooltip: the declaration's doc, then type, default and range.
    w.tooltip = desc.doc.empty() ? "" : desc.doc + "\n";
    w.tooltip += std::string(paramTypeName(desc.type)) + ", default " + desc.defaultValue.dump();
    if (desc.min || desc.max) {
        auto num = [](const std::optional<double>& v, const char* inf) {
            return v ? json(*v).dump() : std::string(inf);
        };
        w.tooltip += ", range [" + num(desc.min, "-inf") + ", " + num(desc.max, "inf") + "]";
    }
    if (!desc.choices.empty()) {
        w.tooltip += ", one of";
        for (const auto& c : desc.choices) w.tooltip += " " + c;
    }
    return w;
}

std::vector<ParamWidget> paramWidgets(const PassReflection& reflection) {
    std::vector<ParamWidget> out;
    for (const auto& p : reflection.params()) out.push_back(paramWidget(p));
    return out;
}

std::string applyParam(RenderGraph& graph, const std::string& pass, const std::string& param,
                       const json& value) {
    try {
        graph.setParam(pass + "." + param, value);
        return "";
    } catch (const std::exception& e) {
        return e.what();
    }
}

std::string parseJsonText(const std::string& text, json& value) {
    try {
        value = json::parse(text);
        return "";
    } catch (const json::parse_error& e) {
        return e.what();
    }
}

}  // namespace loom::inspector
