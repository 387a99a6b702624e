#include "cyc/a/a.hpp"
#include "cyc/c/c.hpp"
