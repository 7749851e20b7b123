# SPDX-License-Identifier: BSD-3-Clause
# make lint: static analysis of libcyl and the frontend; any finding fails (CI runs it).
#   cppcheck (warning, style, performance, portability) and clang-tidy (checks in .clang-tidy).
DEBS_LINT := cppcheck clang-tidy
LINT_C := $(sort $(wildcard libcyl/src/*.c))
LINT_CXX = $(sort $(wildcard frontend/src/*.cpp frontend/src/*/*.cpp frontend/tools/*.cpp))
lint: $(STAMP)/debs-lint $(STAMP)/debs-cv $(STAMP)/debs-calib
	@# variableScope is off: declarations at the top of a block are the core's house style (C89-friendly)
	cppcheck --enable=warning,style,performance,portability --std=c99 --inline-suppr --error-exitcode=1 --suppress=variableScope \
	  --suppress=missingIncludeSystem --quiet -Ilibcyl/include $(LINT_C)
	cppcheck --enable=warning,performance,portability --std=c++17 --language=c++ --inline-suppr --error-exitcode=1 \
	  --suppress=missingIncludeSystem --quiet -Ilibcyl/include -Ifrontend/include $(LINT_CXX)
	clang-tidy --quiet $(LINT_C) -- -std=c99 -Ilibcyl/include
	clang-tidy --quiet $(LINT_CXX) -- -std=c++17 -Ilibcyl/include -Ifrontend/include -Itests/common -I/usr/include/eigen3 $(CV_FLAGS)
	@echo "lint: cppcheck and clang-tidy clean on $(words $(LINT_C)) C and $(words $(LINT_CXX)) C++ files"
	@scripts/spdx.py --check
	@test -f LICENSE && test -f CITATION.cff && echo "lint: LICENSE (BSD-3-Clause) and CITATION.cff present"
.PHONY: lint
