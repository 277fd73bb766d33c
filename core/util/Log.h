#pragma once
#include <cstdio>
#include <fmt/format.h>
#include <string>

namespace loom {

enum class LogLevel { Debug = 0, Info = 1, Warning = 2, Error = 3, Silent = 4 };

void setLogLevel(LogLevel level);
LogLevel logLevel();
void logMessage(LogLevel level, const std::string& text);

template <class... Args>
void logInfo(fmt::format_string<Args...> fmt, Args&&... args) {
    logMessage(LogLevel::Info, fmt::format(fmt, std::forward<Args>(args)...));
}
template <class... Args>
void logWarning(fmt::format_string<Args...> fmt, Args&&... args) {
    logMessage(LogLevel::Warning, fmt::format(fmt, std::forward<Args>(args)...));
}
template <class... Args>
void logDebug(fmt::format_string<Args...> fmt, Args&&... args) {
    if (logLevel() <= LogLevel::Debug)
        logMessage(LogLevel::Debug, fmt::format(fmt, std::forward<Args>(args)...));
}

}  // namespace loom
