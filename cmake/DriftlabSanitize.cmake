# DRIFTLAB_SANITIZE="address;undefined" builds everything with those sanitizers.
if(DRIFTLAB_SANITIZE)
  foreach(s IN LISTS DRIFTLAB_SANITIZE)
    if(NOT s MATCHES "^(address|undefined|thread|leak)$")
      message(FATAL_ERROR "DRIFTLAB_SANITIZE: unknown sanitizer '${s}' (expected address, undefined, thread or leak)")
    endif()
  endforeach()
  list(JOIN DRIFTLAB_SANITIZE "," san)
  add_compile_options(-fsanitize=${san} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  # -O1 -g1 after the build type's flags (the last -O and -g win): ASan's recommended level, with
  # line tables for its reports. Compiling fusion/eskf.cpp with ASan and UBSan took 114 s at
  # RelWithDebInfo's -O2 -g and 62 s at -O1 -g1 (2-core machine, 2026-11-27).
  add_compile_options(-O1 -g1)
  add_link_options(-fsanitize=${san})
  message(STATUS "driftlab: sanitizers ${san}")
  # Every test and fuzz replay (and the programs they start): OSMesa's process-lifetime
  # allocations are not leaks (tests/lsan.supp).
  set(DRIFTLAB_SANITIZER_ENV
      "LSAN_OPTIONS=suppressions=${PROJECT_SOURCE_DIR}/tests/lsan.supp:print_suppressions=0")
endif()
