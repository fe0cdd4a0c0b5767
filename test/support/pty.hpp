// PseudoTerminal: a real kernel pseudo-terminal pair (posix_openpt) for serial tests. The code under
// test opens slave_path() exactly as it would open a UART; the test plays the device on master_fd().
// Host (Linux) tests only. The master is closed on destruction.
#pragma once

#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include <cstring>

namespace qnav::test {

class PseudoTerminal {
 public:
  PseudoTerminal() {
    master_ = posix_openpt(O_RDWR | O_NOCTTY);
    if (master_ >= 0 && grantpt(master_) == 0 && unlockpt(master_) == 0) {
      const char* n = ptsname(master_);
      if (n != nullptr) std::strncpy(slave_, n, sizeof slave_ - 1);
    }
  }
  ~PseudoTerminal() {
    if (master_ >= 0) close(master_);
  }
  PseudoTerminal(const PseudoTerminal&) = delete;
  PseudoTerminal& operator=(const PseudoTerminal&) = delete;

  // True when the pair exists and the slave has a name.
  bool ok() const { return master_ >= 0 && slave_[0] != '\0'; }
  int master_fd() const { return master_; }
  // The device goes away (unplugged USB adapter, powered-down sensor): the slave side sees a hang-up.
  void close_master() {
    if (master_ >= 0) close(master_);
    master_ = -1;
  }
  const char* slave_path() const { return slave_; }

 private:
  int master_ = -1;
  char slave_[128] = {};
};

}  // namespace qnav::test
