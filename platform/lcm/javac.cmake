# Compiles every generated .java file of one folder (the list is only known after lcm-gen ran).
file(GLOB _java_files ${SOURCES}/*.java)
execute_process(COMMAND ${JAVAC} -nowarn -source 8 -target 8 -cp ${CLASSPATH} -d ${OUT} ${_java_files}
                RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "javac failed on the generated LCM Java classes")
endif()
