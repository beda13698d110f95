# The allowed dependency directions between the project's modules (docs/architecture.md), checked at
# configure time: a module's library links, and its sources include headers of, only the modules
# listed for it. Adding an arrow is a design decision: change it here and in docs/architecture.md.

set(FURUTA_MODULE_DEPENDENCIES
  "common:"
  "model:"
  "interval:common"
  "firmware_bridge:"
  "simulator:firmware_bridge,model"
  "config:firmware_bridge,simulator,model"
  "lcmtypes:"
  "command_auth:lcmtypes,common"
  "session_log:lcmtypes,firmware_bridge"
  "daemon:firmware_bridge,simulator,config,session_log,lcmtypes,model,command_auth,common"
  "identification:model,interval,config,session_log,validated"
  "validated:model,interval,common"
  "pipeline:identification,validated,session_log,config,model,interval"
  "report:pipeline,identification,validated,session_log,config,model,interval,common"
  "app:firmware_bridge,simulator,config,daemon,command_auth,session_log,identification,validated,pipeline,report,model,interval,common,lcmtypes"
)

function(furuta_check_module_dependencies)
  set(modules "")
  foreach(entry IN LISTS FURUTA_MODULE_DEPENDENCIES)
    string(REPLACE ":" ";" parts "${entry}")
    list(GET parts 0 module)
    list(LENGTH parts n)
    set(allowed "")
    if(n GREATER 1)
      list(GET parts 1 allowed_text)
      string(REPLACE "," ";" allowed "${allowed_text}")
    endif()
    set(allowed_${module} "${allowed}")
    list(APPEND modules ${module})
  endforeach()

  foreach(module IN LISTS modules)
    set(target furuta_${module})
    if(NOT TARGET ${target} OR NOT IS_DIRECTORY ${PROJECT_SOURCE_DIR}/${module})
      continue()
    endif()
    # Links: every furuta library named in the module's own link lists.
    get_target_property(type ${target} TYPE)
    set(links "")
    if(NOT type STREQUAL "INTERFACE_LIBRARY")
      get_target_property(private_links ${target} LINK_LIBRARIES)
      if(private_links)
        list(APPEND links ${private_links})
      endif()
    endif()
    get_target_property(interface_links ${target} INTERFACE_LINK_LIBRARIES)
    if(interface_links)
      list(APPEND links ${interface_links})
    endif()
    foreach(link IN LISTS links)
      if(link MATCHES "^(\\$<LINK_ONLY:)?furuta(::|_)([a-z_]+)>?$")
        set(dep ${CMAKE_MATCH_3})
        if(NOT dep STREQUAL module AND NOT dep IN_LIST allowed_${module})
          message(FATAL_ERROR "module ${module} links furuta::${dep}, which it may not "
                              "(cmake/ModuleDependencies.cmake, docs/architecture.md)")
        endif()
      endif()
    endforeach()
    # Includes: every "furuta/<module>/..." header named by the module's sources.
    file(GLOB_RECURSE sources ${PROJECT_SOURCE_DIR}/${module}/*.cpp ${PROJECT_SOURCE_DIR}/${module}/*.hpp)
    foreach(source IN LISTS sources)
      file(STRINGS ${source} includes REGEX "^#include [<\"]furuta/")
      foreach(line IN LISTS includes)
        if(line MATCHES "^#include [<\"]furuta/([a-z_]+)/")
          set(dep ${CMAKE_MATCH_1})
          if(NOT dep STREQUAL module AND NOT dep IN_LIST allowed_${module})
            file(RELATIVE_PATH where ${PROJECT_SOURCE_DIR} ${source})
            message(FATAL_ERROR "${where} includes furuta/${dep}/, which module ${module} may not "
                                "use (cmake/ModuleDependencies.cmake, docs/architecture.md)")
          endif()
        endif()
      endforeach()
    endforeach()
  endforeach()
endfunction()
