// Anchors the nav_test_support library (its helpers are header-only; see nav/testing/).
#include "nav/testing/data.h"
