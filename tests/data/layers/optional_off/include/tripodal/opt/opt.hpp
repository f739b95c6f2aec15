// Fixture: a header of the optional area, which links low.
#pragma once
#include "tripodal/low/low.hpp"
