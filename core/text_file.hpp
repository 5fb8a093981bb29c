#pragma once
// Text files written so that a reader never sees a partial one (run.xmf, scene.toml, DONE, cgd-export's
// header, module and tables).
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace cgd {

/// Writes every (path, text): each to `path.tmp` in its own folder, fsync'd; once all are written, each is
/// renamed into place (so a set of files appears together or not at all). On a failure the temporaries are
/// removed, nothing is renamed, and a RunError names the temporary and the system's reason
/// ("run.xmf.tmp: cannot write (No space left on device)").
void write_text_files_atomically(const std::vector<std::pair<std::filesystem::path, std::string>>& files);

/// One file: write_text_files_atomically({{path, text}}).
void write_text_atomically(const std::filesystem::path& path, const std::string& text);

}  // namespace cgd
