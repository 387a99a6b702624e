// Module a includes b, b includes a: a cycle the module check must find.
#include "cyc/b/b.hpp"
