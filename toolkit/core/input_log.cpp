#include "toolkit/core/input_log.h"

#include <algorithm>

namespace ptc {

namespace {
thread_local InputLog* t_current = nullptr;
}

InputLog::InputLog() : outer_(t_current) { t_current = this; }

InputLog::~InputLog() { t_current = outer_; }

void note_input_file(const std::filesystem::path& path) {
  std::error_code ec;
  std::filesystem::path abs = std::filesystem::absolute(path, ec);
  if (ec) abs = path;
  abs = abs.lexically_normal();
  for (InputLog* log = t_current; log; log = log->outer_)
    if (std::find(log->files_.begin(), log->files_.end(), abs) == log->files_.end()) log->files_.push_back(abs);
}

}  // namespace ptc
