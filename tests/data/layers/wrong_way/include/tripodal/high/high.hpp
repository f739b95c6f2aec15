#pragma once
#include "tripodal/mid/mid.hpp"
