// threaded_marginals_launcher (filter/marginals_launcher.h).
#include "nav/daemon/filter/marginals_launcher.h"

#include <future>
#include <memory>
#include <utility>

namespace nav::daemon {

core::MarginalsLauncher threaded_marginals_launcher() {
  return [](core::MarginalsJob job) -> core::MarginalsJob {
    // std::async: the job's exception reaches the caller of get(), on the filter thread.
    std::shared_future<std::shared_ptr<const core::ExactMarginals>> result =
        std::async(std::launch::async, std::move(job)).share();
    return [result] { return result.get(); };
  };
}

}  // namespace nav::daemon
