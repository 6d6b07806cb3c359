// LeakSanitizer suppressions for the whole test binary (sanitizer builds only; never called
// otherwise). This strong definition takes precedence over the weak one next to the Gmsh tests
// and repeats its entry: libgmsh 4.8 leaks small allocations while meshing that gmsh::finalize
// does not free. The snapshot and plot tests run Mesa's OSMesa (with LLVM) and PLplot (its driver
// loader libltdl, cairo, fontconfig, pango) in this process; those system libraries keep one-time
// allocations they never free.

extern "C" __attribute__((visibility("default"))) const char* __lsan_default_suppressions() {
  return "leak:libgmsh.so\n"
         "leak:libOSMesa.so\nleak:libgallium\nleak:libLLVM\nleak:libglapi.so\n"
         "leak:libplplot.so\nleak:libcairo.so\nleak:libfontconfig.so\nleak:libpango\n"
         "leak:libfreetype.so\nleak:libltdl.so\n"
         // OpenIGTLink 1.11's POLYDATA packing frees its info struct but not two of the
         // blocks igtl_polydata_alloc_info allocates in it (112 bytes per message).
         "leak:igtl_polydata_alloc_info\n";
}

/// AddressSanitizer's defaults (sanitizer builds only; never called otherwise). Debian 12's
/// libfreeimage, loaded through Gmsh's OpenCASCADE (libTKService), frees at exit with free() a
/// block it allocated with operator new(nothrow); clang's ASan reports that alloc-dealloc
/// mismatch and aborts every program as it exits. Not GiPSi's allocation, and ASan 14 cannot
/// suppress that report per library, so the mismatch check is off (GiPSi allocates through
/// containers and smart pointers). ASAN_OPTIONS still take precedence.
extern "C" __attribute__((visibility("default"))) const char* __asan_default_options() {
  return "alloc_dealloc_mismatch=0";
}
