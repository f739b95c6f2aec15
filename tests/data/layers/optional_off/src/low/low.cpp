// Fixture: a source of low.
#include "tripodal/low/low.hpp"
