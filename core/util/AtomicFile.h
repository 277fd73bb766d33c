#pragma once
// Every file Loom writes goes through these, so that a failed write (full disk, file-size
// limit, missing permission) never leaves a damaged file where a good one was: the content
// goes to a temporary file in the target's directory, every write, flush and close is checked,
// and only then is it renamed over the target. Errors are UserError naming the path.
#include <functional>
#include <string>

namespace loom {

// Calls write(tmpPath) to produce the file, then renames tmpPath over `path`. The temporary
// name keeps the extension (image writers choose the format by it). `what` names the kind of
// file in messages ("image", "CSV file"). A target that exists and is not a regular file
// (/dev/null, a pipe) is written in place. The parent directory is created.
void writeFileAtomic(const std::string& path, const std::string& what,
                     const std::function<void(const std::string& tmpPath)>& write);

// writeFileAtomic for text: every byte is written and flushed, or it throws.
void writeTextFileAtomic(const std::string& path, const std::string& what,
                         const std::string& content);

// Throws UserError when `path` could not be written: its directory cannot be created or
// written, or it names a directory. Run before rendering so that a bad output path fails in
// seconds, not after the render.
void checkWritable(const std::string& path, const std::string& what);

}  // namespace loom
