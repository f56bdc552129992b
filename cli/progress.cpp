#include "progress.h"

#include <unistd.h>

#include <cstdio>

namespace vcut::cli {

ProgressBar::ProgressBar(bool enabled) : enabled_(enabled && ::isatty(STDERR_FILENO)) {}
ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(const std::string& stage, std::size_t done, std::size_t total) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (stage != stage_) {
    stage_ = stage;
    stage_start_ = now;
  } else if (done < total && now - last_draw_ < std::chrono::milliseconds(100)) {
    return;
  }
  last_draw_ = now;
  const double fraction = total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 0.0;
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(fraction * kWidth);
  char bar[kWidth + 1];
  for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
  bar[kWidth] = '\0';
  const double elapsed = std::chrono::duration<double>(now - stage_start_).count();
  std::fprintf(stderr, "\r%-8s [%s] %5.1f%% %zu/%zu", stage.c_str(), bar, 100.0 * fraction, done, total);
  if (fraction > 0.0 && fraction < 1.0)
    std::fprintf(stderr, "  ETA %.0f s   ", elapsed * (1.0 - fraction) / fraction);
  else
    std::fprintf(stderr, "              ");
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressBar::finish() {
  if (drawn_) std::fprintf(stderr, "\r%80s\r", "");
  drawn_ = false;
}

}  // namespace vcut::cli
