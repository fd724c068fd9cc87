#include "kestrel/sim/progress.hpp"

#include <unistd.h>

namespace kestrel::sim {

ProgressLine::ProgressLine(std::FILE* out, bool enabled, double total, const char* unit)
    : out_(out), enabled_(enabled && out != nullptr && total > 0), total_(total), unit_(unit != nullptr ? unit : "env-steps"),
      t0_(std::chrono::steady_clock::now()) {}

bool ProgressLine::stderr_is_terminal() { return ::isatty(STDERR_FILENO) == 1; }

namespace {
// 1234567 -> "1.23M": the figures of a progress line, short enough to keep it on one line.
std::string si(double v) {
  char b[32];
  if (v < 1e3) std::snprintf(b, sizeof b, "%.0f", v);
  else if (v < 1e6) std::snprintf(b, sizeof b, "%.1fk", v / 1e3);
  else if (v < 1e9) std::snprintf(b, sizeof b, "%.2fM", v / 1e6);
  else std::snprintf(b, sizeof b, "%.2fG", v / 1e9);
  return b;
}
}  // namespace

std::string ProgressLine::format(double done, double total, double elapsed_s, const char* unit) {
  const double rate = elapsed_s > 0 ? done / elapsed_s : 0;
  char left[48] = "? s left";
  if (rate > 0) {
    const double s = (total - done) / rate;
    if (s < 60) std::snprintf(left, sizeof left, "%.1f s left", s);
    else if (s < 3600) std::snprintf(left, sizeof left, "%d min %02d s left", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
    else std::snprintf(left, sizeof left, "%d h %02d min left", static_cast<int>(s) / 3600, static_cast<int>(s) / 60 % 60);
  }
  char b[192];
  std::snprintf(b, sizeof b, "  %s %s / %s (%.0f%%), %s %s/s, %s", unit, si(done).c_str(), si(total).c_str(),
                total > 0 ? 100.0 * done / total : 0.0, si(rate).c_str(), unit, left);
  return b;
}

void ProgressLine::update(double done) {
  if (enabled_) update_at(done, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count());
}

void ProgressLine::update_at(double done, double elapsed_s) {
  if (!enabled_) return;
  last_done_ = done;
  if (elapsed_s < kFirstAfterS || (last_print_s_ >= 0 && elapsed_s - last_print_s_ < kIntervalS)) return;
  last_print_s_ = elapsed_s;
  // \r + erase to the end of the line: a terminal only (the line is enabled only there).
  std::fprintf(out_, "\r%s\033[K", format(done, total_, elapsed_s, unit_).c_str());
  std::fflush(out_);
  ++lines_;
  shown_ = true;
}

void ProgressLine::clear() {
  if (!enabled_ || !shown_) return;
  std::fputs("\r\033[K", out_);
  std::fflush(out_);
  shown_ = false;
}

void ProgressLine::finish() {
  if (enabled_) finish_at(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count());
}

void ProgressLine::finish_at(double elapsed_s) {
  if (!enabled_ || lines_ == 0) return;
  std::fprintf(out_, "\r%s\033[K\n", format(last_done_, total_, elapsed_s, unit_).c_str());
  std::fflush(out_);
  ++lines_;
  shown_ = false;
  enabled_ = false;  // once
}

}  // namespace kestrel::sim
