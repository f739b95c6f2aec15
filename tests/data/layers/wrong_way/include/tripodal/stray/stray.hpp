// A header folder without an area library.
#pragma once
