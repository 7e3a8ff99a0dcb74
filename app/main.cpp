// `driftlab`: the command line (app/driftlab_main.cpp), nothing registered besides the
// built-in VOs.
#include "app/driftlab_main.hpp"

int main(int argc, char** argv) { return driftlab::app::driftlab_main(argc, argv); }
