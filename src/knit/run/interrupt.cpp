#include "knit/run/interrupt.hpp"

#include <csignal>

namespace knit {

namespace {

volatile std::sig_atomic_t g_signal = 0;
struct sigaction g_old_int, g_old_term;

extern "C" void on_signal(int sig) {
  if (g_signal != 0) {
    // the second signal: the default action (the process ends at once)
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    return;
  }
  g_signal = sig;
}

void install(struct sigaction* old_int, struct sigaction* old_term) {
  g_signal = 0;
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, old_int);
  sigaction(SIGTERM, &sa, old_term);
}

}  // namespace

InterruptHandler::InterruptHandler() {
  install(&g_old_int, &g_old_term);
}

InterruptHandler::~InterruptHandler() {
  sigaction(SIGINT, &g_old_int, nullptr);
  sigaction(SIGTERM, &g_old_term, nullptr);
}

void handle_interrupts_until_exit() {
  install(nullptr, nullptr);
}

const char* interrupt_signal_name(int signal) {
  return signal == SIGINT ? "SIGINT" : "SIGTERM";
}

int interrupt_signal() {
  return g_signal;
}

void clear_interrupt() {
  g_signal = 0;
}

void request_interrupt(int signal) {
  g_signal = signal;
}

}  // namespace knit
