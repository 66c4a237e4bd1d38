#pragma once
// Which LCM URL the service publishes on. `navtool survey` (config/sim.yaml) publishes on udpm
// with ttl=0 so that tools on the same machine (lcm-logger --lcm-url=..., lcm-spy) see the
// traffic; a host without a multicast route (no network, a container) cannot open udpm. Then
// the survey falls back to in-process memq:// with a warning that names the fix, so that the
// simulated dive, its outputs and the report still come out; a URL given with --lcm-url is an
// explicit request and its failure stops the survey (exit 2) with the same fix.

#include <string>

namespace nav::daemon::service {

/// "cannot open LCM at 'URL'" and, for udpm, the likely cause and the fix (the replay and live
/// modes log it and run without publishing).
std::string lcm_open_error(const std::string& url);

/// True if LCM can be opened at `url` (it is closed again).
bool lcm_url_opens(const std::string& url);

/// `url` if it opens; otherwise, with `fallback_to_memq`, logs a warning and returns "memq://",
/// and without it throws std::invalid_argument with the reason and the fix.
std::string usable_lcm_url(const std::string& url, bool fallback_to_memq);

}  // namespace nav::daemon::service
