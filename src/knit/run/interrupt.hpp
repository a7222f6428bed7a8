#pragma once
// Interrupting a run cleanly: while an InterruptHandler is alive, the first SIGINT or
// SIGTERM only sets a flag, which the runner reads after every step (it then finishes the
// step, writes the state and a summary with status "interrupted", and returns); a second
// signal ends the process at once, as it would without the handler.
namespace knit {

class InterruptHandler {
 public:
  InterruptHandler();   ///< installs the handlers for SIGINT and SIGTERM
  ~InterruptHandler();  ///< restores the previous ones
  InterruptHandler(const InterruptHandler&) = delete;
  InterruptHandler& operator=(const InterruptHandler&) = delete;
};

/// Installs the handlers for the rest of the process, never restored: a program's main
/// calls it first. A signal that arrives once the work is done (while the program writes
/// its last lines, destroys its statics or, under the sanitizers, checks for leaks) then
/// sets the flag that nothing reads any more, and the program exits with its own status
/// rather than being killed with a finished run's outputs on disk.
void handle_interrupts_until_exit();

/// The signal received since the last clear (SIGINT, SIGTERM), or 0.
int interrupt_signal();
/// "SIGINT" or "SIGTERM", for messages about a received signal.
const char* interrupt_signal_name(int signal);
/// Forgets a received signal.
void clear_interrupt();
/// Acts as if `signal` had been received once (tests, and callers that stop a run from
/// another thread).
void request_interrupt(int signal);

}  // namespace knit
