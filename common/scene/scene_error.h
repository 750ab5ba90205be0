// The one exception every scene front end throws. Its message always starts with "file:line: " (or
// "file: " when no line applies, e.g. an unreadable file) and names the construct that is wrong.
#pragma once
#include <stdexcept>
#include <string>

#include "common/core/clip.h"

namespace mlt {

class SceneError : public std::runtime_error {
 public:
  static constexpr size_t kMaxWhat = 600;  // the description is cut there: it may echo a huge attribute value
  SceneError(const std::string& file, int line, const std::string& what)
      : std::runtime_error(line > 0 ? file + ":" + std::to_string(line) + ": " + clipForMessage(what, kMaxWhat)
                                    : file + ": " + clipForMessage(what, kMaxWhat)),
        file_(file),
        line_(line) {}
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  std::string file_;
  int line_;
};

}  // namespace mlt
