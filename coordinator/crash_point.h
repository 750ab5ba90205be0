// Test-only crash points: the coordinator kills itself (SIGKILL, as `kill -9` would) at a named point,
// so a crash test places the crash exactly where it means to, with no timing. Off unless the hidden
// flag --debug-crash-at NAME[:N] is given (then the N-th time the point is reached; N defaults to 1).
//   upload-received  a task's film is received and checked, not yet stored
//   upload-recorded  it is stored and accepted, the reply not yet sent
//   final-merge      the final image is written under its temporary name, not yet renamed; not DONE yet
#pragma once
#include <string>

namespace mlt::farm {

// Arms the crash point; throws std::invalid_argument for an unknown name or a bad count.
void armCrashPoint(const std::string& spec);
// Dies here if this is the armed point's N-th arrival; otherwise nothing (one relaxed load when unarmed).
void crashPoint(const char* name);

}  // namespace mlt::farm
