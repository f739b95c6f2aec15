// Fixture: a source of the optional area.
#include "tripodal/opt/opt.hpp"
