# The C++ frontend: frontend/src/*.cpp -> $(BUILD)/frontend/libcylfe.a; tools in frontend/tools/.
FRONTEND_SRCS := $(sort $(wildcard frontend/src/*.cpp))
FRONTEND_OBJS := $(FRONTEND_SRCS:frontend/src/%.cpp=$(BUILD)/frontend/%.o)
FRONTEND_A := $(BUILD)/frontend/libcylfe.a
FRONTEND_HDRS := $(wildcard frontend/include/cylfe/*.hpp)
CV_FLAGS = $(shell pkg-config --cflags opencv4 2>/dev/null)
CV_LIBS = $(shell pkg-config --libs opencv4 2>/dev/null)

$(BUILD)/frontend/%.o: frontend/src/%.cpp $(FRONTEND_HDRS) $(wildcard libcyl/include/cyl/*.h) | $(STAMP)/debs-cv
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) $(CV_FLAGS) -c $< -o $@

$(FRONTEND_A): $(FRONTEND_OBJS)
	rm -f $@.tmp && ar rcs $@.tmp $^ && mv $@.tmp $@

# ---- V4L2 against the kernel's vivid driver, under qemu (part of make test) --------------
DEBS_VIVID := qemu-system-x86 busybox-static cpio kmod xz-utils binutils
VIVID_SRCS := tests/v4l2/vivid_test.cpp frontend/src/v4l2.cpp frontend/src/rawlog.cpp
$(BUILD)/vivid_test: $(VIVID_SRCS) $(FRONTEND_HDRS) lib
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) -static $(VIVID_SRCS) -o $@ $(LIBCYL_A) -lm
TEST_EXTRA += $(STAMP)/debs-vivid $(BUILD)/vivid_test
TEST_EXTRA_BINS += scripts/vivid-test.sh:$(BUILD)/vivid_test
vivid-test: $(STAMP)/debs-vivid $(BUILD)/vivid_test
	scripts/vivid-test.sh $(BUILD)/vivid_test
.PHONY: vivid-test
