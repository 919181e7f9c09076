#include "toolkit/core/input_log.h"

namespace ptc {

namespace {
thread_local InputLog* t_current = nullptr;
}

InputLog::InputLog() : outer_(t_current) { t_current = this; }

InputLog::~InputLog() { t_current = outer_; }

void note_input_file(const std::filesystem::path& path) {
  if (!t_current) return;  // (the per-frame reads of a sequence, after the scene was opened)
  std::error_code ec;
  std::filesystem::path abs = std::filesystem::absolute(path, ec);
  if (ec) abs = path;
  abs = abs.lexically_normal();
  for (InputLog* log = t_current; log; log = log->outer_)
    if (log->seen_.insert(abs.string()).second) log->files_.push_back(abs);
}

}  // namespace ptc
