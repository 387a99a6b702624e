// c depends on nothing: not in the cycle.
int c();
