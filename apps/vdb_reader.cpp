// scatterlab-vdb-reader: the program in which scatterlab parses VDB files (media/vdb.h).
#include "media/vdb.h"

int main(int argc, char** argv) {
  return scatterlab::vdbReaderMain(argc, argv);
}
