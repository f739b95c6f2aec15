// Compiles tests/CMakeLists.txt's precompiled header (tripodal_test_pch) once; the suites reuse it.
