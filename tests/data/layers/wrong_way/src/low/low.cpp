#include "tripodal/low/low.hpp"

#include "tripodal/mid/mid.hpp"
