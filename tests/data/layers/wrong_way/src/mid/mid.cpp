#include "tripodal/mid/mid.hpp"
#include "tripodal/priv/priv.hpp"
  #  include "../high/helper.hpp"
// #include "tripodal/high/high.hpp" (a comment, not an include)
