#pragma once
// The daemon's edge for image registrations: navlcm::registration_t (the vision stage's LCM
// message, a dive log's NAV_REGISTRATION events) to the filter's core::Registration, and the
// names the daemon uses for the registration table.

#include <navlcm/registration_t.hpp>

#include "nav/core/navigation/registration_table.h"

namespace nav::daemon {

using core::Registration;
using core::RegistrationResult;
using core::RegistrationTable;

/// The message's fields; its covariance is row-major 5 x 5.
core::Registration registration_from_message(const navlcm::registration_t& message);

}  // namespace nav::daemon
