// Fixture: an area at the bottom.
#pragma once
