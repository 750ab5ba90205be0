// The one exception every scene front end throws. Its message always starts with "file:line: " (or
// "file: " when no line applies, e.g. an unreadable file) and names the construct that is wrong.
#pragma once
#include <stdexcept>
#include <string>

namespace mlt {

class SceneError : public std::runtime_error {
 public:
  SceneError(const std::string& file, int line, const std::string& what)
      : std::runtime_error(line > 0 ? file + ":" + std::to_string(line) + ": " + what : file + ": " + what),
        file_(file),
        line_(line) {}
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  std::string file_;
  int line_;
};

}  // namespace mlt
