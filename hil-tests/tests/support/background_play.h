#pragma once
// Plays a dive (DivePlayer::play) on a thread of its own while the test handles LCM or a
// device on its thread: done() once the dive is played, finish() stops the player if it is
// still playing, joins and returns its report. The destructor stops and joins too, so a test
// that fails an ASSERT before finish() does not leave a joinable thread behind.
#include <atomic>
#include <thread>

#include "nav/hil/dive_player.h"

namespace nav::hil::test {

class BackgroundPlay {
 public:
  explicit BackgroundPlay(DivePlayer& player)
      : thread_([this, &player] {
          report_ = player.play(stop_);
          done_.store(true);
        }) {}
  ~BackgroundPlay() { (void)finish(); }
  BackgroundPlay(const BackgroundPlay&) = delete;
  BackgroundPlay& operator=(const BackgroundPlay&) = delete;

  bool done() const { return done_.load(); }
  PlayReport finish() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
    return report_;
  }

 private:
  std::atomic<bool> stop_{false}, done_{false};
  PlayReport report_;   ///< written by the thread until it is joined
  std::thread thread_;  ///< last: starts once the members above exist
};

}  // namespace nav::hil::test
