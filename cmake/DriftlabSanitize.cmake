# DRIFTLAB_SANITIZE="address;undefined" builds everything with those sanitizers.
if(DRIFTLAB_SANITIZE)
  foreach(s IN LISTS DRIFTLAB_SANITIZE)
    if(NOT s MATCHES "^(address|undefined|thread|leak)$")
      message(FATAL_ERROR "DRIFTLAB_SANITIZE: unknown sanitizer '${s}' (expected address, undefined, thread or leak)")
    endif()
  endforeach()
  list(JOIN DRIFTLAB_SANITIZE "," san)
  add_compile_options(-fsanitize=${san} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  # -O2 -g1 after the build type's flags (the last -O and -g win): line tables for the reports
  # (full -g cost most of the compile time: fusion/eskf.cpp with ASan and UBSan 114 s at -O2 -g,
  # 62 s at -O1 -g1). -O2 rather than ASan's suggested -O1: clang compiles scenes/
  # as fast at either, and at -O1 leaves Eigen's small vectors uninlined (a river scene and one
  # frame: 5.9 s at -O1, 3.9 s at -O2).
  add_compile_options(-O2 -g1)
  add_link_options(-fsanitize=${san})
  message(STATUS "driftlab: sanitizers ${san}")
  # Every test and fuzz replay (and the programs they start): OSMesa's process-lifetime
  # allocations are not leaks (tests/lsan.supp).
  set(DRIFTLAB_SANITIZER_ENV
      "LSAN_OPTIONS=suppressions=${PROJECT_SOURCE_DIR}/tests/lsan.supp:print_suppressions=0")
endif()
