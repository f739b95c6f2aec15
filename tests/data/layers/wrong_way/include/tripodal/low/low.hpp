// The bottom area: including the top one is the wrong way.
#pragma once
#include "tripodal/high/high.hpp"
