#pragma once
#include "tripodal/low/low.hpp"
