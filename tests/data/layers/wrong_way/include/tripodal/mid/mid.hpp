// A public header may include PUBLIC links only: priv is linked PRIVATE.
#pragma once
#include "tripodal/low/low.hpp"
#include "tripodal/priv/priv.hpp"
