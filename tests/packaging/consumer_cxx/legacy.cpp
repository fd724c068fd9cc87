// "Legacy" code that this project's flags accept and Kestrel's would not: C-style casts
// (-Wold-style-cast) and a local that shadows another (-Wshadow). If the package pushed Kestrel's
// warning policy onto the consumer, this file would break its build.
bool legacy_ok();

bool legacy_ok() {
  double scale = 0.5;
  int half = (int)(10 * scale);
  {
    int half = (int)scale;
    if (half != 0) return false;
  }
  return half == 5;
}
