// Outputs are written atomically: to a temporary file beside the target, then renamed
// over it, so a reader never sees a half-written file and a failure leaves none behind.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace vcut::io {

// Calls write(temporary_path), then renames it to `path`; removes the temporary on failure.
// Errors (cannot create, cannot rename) are vcut::InputError naming `path`.
void write_atomically(const std::string& path, const std::function<void(const std::string&)>& write);
void write_text_atomically(const std::string& path, const std::string& text);
// The same for text written as it is made: write(out) fills the temporary file; a file that
// cannot be created or written in full (disk full) is an InputError naming `path`.
void write_stream_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

// Creates the folder (and parents); an InputError when it cannot be created or written.
void ensure_writable_folder(const std::string& folder);

}  // namespace vcut::io
