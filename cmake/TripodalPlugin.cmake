# tripodal_add_plugin(<target> <source>...)
#
# A shared-library plugin (docs/plugins.md): a MODULE library <target>.so whose source defines its
# entry points with TRIPODAL_REGISTER_PLUGINS (tripodal/robot/plugin_library.hpp), loaded by
# `tripodal run --plugin`, `tripodal describe --plugin`, `tripodal-net check --plugin`, the test
# harnesses, or a profile's `plugins:` list. Installed with the package (find_package(tripodal)
# brings it) and used by tripodal's own tests.
#
# The plugin links the static tripodal libraries it uses; their symbols, and the plugin's own, stay
# inside it (hidden visibility, --exclude-libs), so that only the two entry points are exported
# and the host's copy of the framework and the plugin's never bind to each other by name.
function(tripodal_add_plugin target)
  if(NOT ARGN)
    message(FATAL_ERROR "tripodal_add_plugin(${target}): give the plugin's source files")
  endif()
  add_library(${target} MODULE ${ARGN})
  set_target_properties(${target} PROPERTIES PREFIX "" CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
  target_compile_features(${target} PRIVATE cxx_std_20)
  target_link_libraries(${target} PRIVATE tripodal::tripodal)
  if(NOT APPLE)
    target_link_options(${target} PRIVATE "LINKER:--exclude-libs,ALL")
  endif()
endfunction()
