# raybundle: one non-recursive GNU Makefile. `make` builds build/raybundle and
# build/libraybundle.a (SPIR-V included); `make check` runs every test; see README.md.

PREFIX ?= /usr/local
DESTDIR ?=
BINDIR ?= $(PREFIX)/bin
MANDIR ?= $(PREFIX)/share/man
DATADIR ?= $(PREFIX)/share/raybundle
PKG_CONFIG ?= pkg-config
GLSLANG ?= glslangValidator
BUILD ?= build

CC ?= cc
CXX ?= c++
CFLAGS ?= -O2 -g
CXXFLAGS ?= -O2 -g

ifneq ($(V),1)
Q := @
endif

# OIIO=0 builds without OpenImageIO (the portable build, make dist): EXR and PNG go through
# OpenEXR and libpng in every build; only reading other formats and report thumbnails need it.
OIIO ?= 1
PKGS := vulkan OpenEXR libpng OpenColorIO yaml-0.1 tinygltf libxxhash jansson
ifeq ($(OIIO),1)
PKGS += OpenImageIO
endif
# Deferred (=), so a fresh machine gets them after scripts/install-deps.sh has run.
PKG_CFLAGS = $(shell $(PKG_CONFIG) --cflags $(PKGS) 2>/dev/null)
# Embree and meshoptimizer ship no pkg-config file in Debian 12.
PKG_LIBS = $(shell $(PKG_CONFIG) --libs $(PKGS) 2>/dev/null) -lembree3 -lmeshoptimizer -lpthread -lm

WARN := -Wall -Wextra -Wpedantic -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Werror=vla
CXXWARN := -Wall -Wextra
ifneq ($(CI),)
WARN += -Werror
CXXWARN += -Werror
endif
ifeq ($(SANITIZE),1)
SANFLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer
endif

# No fused multiply-adds the source did not ask for: GCC fuses a * b + c across statements by
# default (-ffp-contract=fast) where the target has an FMA, clang within one expression (on), so
# the same source would round differently by compiler, target and optimisation level.
FPFLAGS := -ffp-contract=off

DEPFLAGS = -MMD -MP
# DATADIR is not compiled in: the binary finds its data relative to itself (../share/raybundle),
# so `make install` with another PREFIX installs the same build without rebuilding it.
ALL_CPPFLAGS = -Ilib -I$(BUILD)/shaders -Ishaders/common -D_POSIX_C_SOURCE=200809L \
	-DRB_WITH_OIIO=$(OIIO) $(CPPFLAGS)
ALL_CFLAGS = -std=c11 $(WARN) $(FPFLAGS) $(DEPFLAGS) $(PKG_CFLAGS) $(SANFLAGS) $(CFLAGS)
ALL_CXXFLAGS = -std=c++17 $(CXXWARN) $(FPFLAGS) $(DEPFLAGS) $(PKG_CFLAGS) $(SANFLAGS) $(CXXFLAGS)
ALL_LDFLAGS = $(SANFLAGS) $(LDFLAGS)

LIB_C := $(sort $(wildcard lib/*/*.c))
LIB_CXX := $(sort $(wildcard lib/*/*.cpp))
ifneq ($(OIIO),1)
LIB_CXX := $(filter-out lib/io/oiio_shim.cpp,$(LIB_CXX))
endif
CMD_C := $(sort $(wildcard cmd/*.c))
LIB_OBJ := $(LIB_C:%.c=$(BUILD)/%.o) $(LIB_CXX:%.cpp=$(BUILD)/%.o)
CMD_OBJ := $(CMD_C:%.c=$(BUILD)/%.o)

SHADERS := $(sort $(wildcard shaders/*.vert shaders/*.tesc shaders/*.tese shaders/*.frag shaders/*.comp shaders/*.geom))
SPV_H := $(SHADERS:shaders/%=$(BUILD)/shaders/%.h)

UNIT_SRC := $(sort $(wildcard tests/unit/test_*.c))
UNIT_BIN := $(UNIT_SRC:tests/unit/%.c=$(BUILD)/tests/%)

TOOL_SRC := $(sort $(wildcard tests/tools/*.c))
TOOL_BIN := $(TOOL_SRC:tests/tools/%.c=$(BUILD)/tests/tools/%)

DEPS := $(LIB_OBJ:.o=.d) $(CMD_OBJ:.o=.d) $(UNIT_BIN:=.d) $(TOOL_BIN:=.d) \
	$(SPV_H:=.d)

DEPS_STAMP := $(BUILD)/.deps-ok

.PHONY: all test check check-farm check-dist dist bench demo install uninstall clean lint format deps \
	fuzz update-golden ltc-table
.SECONDARY: $(SPV_H)
all: $(BUILD)/raybundle

# The one place missing Debian packages get installed (scripts/install-deps.sh).
deps $(DEPS_STAMP): scripts/install-deps.sh
	$(Q)scripts/install-deps.sh
	$(Q)mkdir -p $(BUILD) && touch $(DEPS_STAMP)

# Rebuild everything when the flags change.
$(BUILD)/.flags: FORCE
	$(Q)mkdir -p $(BUILD)
	$(Q)echo '$(CC) $(CXX) $(ALL_CPPFLAGS) $(ALL_CFLAGS) $(ALL_CXXFLAGS)' | cmp -s - $@ || \
		echo '$(CC) $(CXX) $(ALL_CPPFLAGS) $(ALL_CFLAGS) $(ALL_CXXFLAGS)' > $@
FORCE:

$(BUILD)/shaders/%.h: shaders/% $(DEPS_STAMP)
	@mkdir -p $(dir $@)
	@echo "  GLSL    $<"
	$(Q)$(GLSLANG) --target-env vulkan1.2 --spirv-val -Ishaders/common \
		--depfile $@.d -x --vn rb_spv_$(subst .,_,$(notdir $<)) -o $@ $< >$@.log || \
		{ sed -e 's/^ERROR: //' $@.log | grep -v '^$$' >&2; rm -f $@; exit 1; }

$(BUILD)/%.o: %.c $(BUILD)/.flags $(DEPS_STAMP) | $(SPV_H)
	@mkdir -p $(dir $@)
	@echo "  CC      $<"
	$(Q)$(CC) $(ALL_CPPFLAGS) $(ALL_CFLAGS) -c -o $@ $<

$(BUILD)/%.o: %.cpp $(BUILD)/.flags $(DEPS_STAMP)
	@mkdir -p $(dir $@)
	@echo "  CXX     $<"
	$(Q)$(CXX) $(ALL_CPPFLAGS) $(ALL_CXXFLAGS) -c -o $@ $<

$(BUILD)/libraybundle.a: $(LIB_OBJ)
	@echo "  AR      $@"
	$(Q)rm -f $@ && ar rcs $@ $^

$(BUILD)/raybundle: $(CMD_OBJ) $(BUILD)/libraybundle.a
	@echo "  LINK    $@"
	$(Q)$(CXX) $(ALL_LDFLAGS) -o $@ $(CMD_OBJ) $(BUILD)/libraybundle.a $(PKG_LIBS)

$(BUILD)/tests/%: tests/unit/%.c $(BUILD)/libraybundle.a $(BUILD)/.flags | $(SPV_H)
	@mkdir -p $(dir $@)
	@echo "  TEST    $@"
	$(Q)$(CC) $(ALL_CPPFLAGS) $(ALL_CFLAGS) $(ALL_LDFLAGS) -o $@ $< $(BUILD)/libraybundle.a \
		$(PKG_LIBS) -lcmocka -lstdc++

$(BUILD)/tests/tools/%: tests/tools/%.c $(BUILD)/libraybundle.a $(BUILD)/.flags
	@mkdir -p $(dir $@)
	@echo "  TOOL    $@"
	$(Q)$(CC) $(ALL_CPPFLAGS) $(ALL_CFLAGS) $(ALL_LDFLAGS) -o $@ $< $(BUILD)/libraybundle.a \
		$(PKG_LIBS) -lstdc++

# The specular lobe's fitted cosines (tools/ltcfit.c): lib/passes/ltc_ggx.inc is its output,
# kept in the tree (the fit takes a minute); `make ltc-table` writes it again, and t0101 refits
# some of its columns.
$(BUILD)/ltcfit: tools/ltcfit.c $(BUILD)/.flags
	@mkdir -p $(dir $@)
	@echo "  CC      $@"
	$(Q)$(CC) -std=c11 $(WARN) $(FPFLAGS) $(CFLAGS) -o $@ $< -lpthread -lm

ltc-table: $(BUILD)/ltcfit
	$(Q)$(BUILD)/ltcfit lib/passes/ltc_ggx.inc

# The demo scene's generator (tools/mkdemo.c): plain C, no library.
$(BUILD)/mkdemo: tools/mkdemo.c $(BUILD)/.flags
	@mkdir -p $(dir $@)
	@echo "  CC      $@"
	$(Q)$(CC) -std=c11 $(WARN) $(FPFLAGS) $(CFLAGS) -o $@ $< -lm

# Fuzz targets: replayed over their committed corpus in `make check` (any compiler), and run
# under libFuzzer by `make fuzz` (clang; FUZZ_SECONDS each).
FUZZ_SRC := $(sort $(wildcard tests/fuzz/fuzz_*.c))
FUZZ_REPLAY := $(FUZZ_SRC:tests/fuzz/%.c=$(BUILD)/tests/fuzz/%)
FUZZ_SECONDS ?= 60

$(BUILD)/tests/fuzz/%: tests/fuzz/%.c tests/fuzz/replay.c $(BUILD)/libraybundle.a $(BUILD)/.flags
	@mkdir -p $(dir $@)
	@echo "  FUZZ    $@"
	$(Q)$(CC) $(ALL_CPPFLAGS) $(ALL_CFLAGS) $(ALL_LDFLAGS) -o $@ $< tests/fuzz/replay.c \
		$(BUILD)/libraybundle.a $(PKG_LIBS) -lstdc++

# The same replays under ASan and UBSan (gcc or clang), also in make check: any report aborts the
# replay and fails t0090. Only what the targets call (core, job, scene, io/timing.c's JSON
# readers, the analysis' sequence scan and bench sets) is compiled again, into $(BUILD)/asan at
# -O1 (fast to compile, still quick to run), so the main build is untouched and the extra time
# stays small.
FUZZ_SAN := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer -O1
FUZZ_SAN_SRC := $(filter lib/core/% lib/job/% lib/scene/% lib/io/timing.c lib/analysis/sequence.c \
	lib/analysis/timing.c,$(LIB_C) $(LIB_CXX))
FUZZ_SAN_OBJ := $(patsubst %,$(BUILD)/asan/%.o,$(basename $(FUZZ_SAN_SRC)))
FUZZ_SAN_BIN := $(FUZZ_SRC:tests/fuzz/%.c=$(BUILD)/asan/tests/fuzz/%)
FUZZ_SAN_LIBS = $(shell $(PKG_CONFIG) --libs yaml-0.1 tinygltf libxxhash jansson 2>/dev/null) \
	-lmeshoptimizer -lm
FUZZ_SAN_DEPS := $(FUZZ_SAN_OBJ:.o=.d) $(FUZZ_SAN_BIN:=.d) $(BUILD)/asan/tests/fuzz/replay.d

$(BUILD)/asan/.flags: FORCE
	$(Q)mkdir -p $(BUILD)/asan
	$(Q)echo '$(CC) $(CXX) $(ALL_CPPFLAGS) $(ALL_CFLAGS) $(ALL_CXXFLAGS) $(FUZZ_SAN)' | \
		cmp -s - $@ || \
		echo '$(CC) $(CXX) $(ALL_CPPFLAGS) $(ALL_CFLAGS) $(ALL_CXXFLAGS) $(FUZZ_SAN)' > $@

$(BUILD)/asan/%.o: %.c $(BUILD)/asan/.flags $(DEPS_STAMP)
	@mkdir -p $(dir $@)
	@echo "  CC      $@"
	$(Q)$(CC) $(ALL_CPPFLAGS) $(ALL_CFLAGS) $(FUZZ_SAN) -c -o $@ $<

$(BUILD)/asan/%.o: %.cpp $(BUILD)/asan/.flags $(DEPS_STAMP)
	@mkdir -p $(dir $@)
	@echo "  CXX     $@"
	$(Q)$(CXX) $(ALL_CPPFLAGS) $(ALL_CXXFLAGS) $(FUZZ_SAN) -c -o $@ $<

$(FUZZ_SAN_BIN): $(BUILD)/asan/tests/fuzz/%: $(BUILD)/asan/tests/fuzz/%.o \
		$(BUILD)/asan/tests/fuzz/replay.o $(FUZZ_SAN_OBJ)
	@echo "  FUZZ    $@"
	$(Q)$(CXX) $(FUZZ_SAN) $(ALL_LDFLAGS) -o $@ $^ $(FUZZ_SAN_LIBS)

fuzz:
	$(Q)$(MAKE) --no-print-directory BUILD=$(BUILD)-fuzz CC=clang CXX=clang++ \
		SANITIZE=1 CFLAGS="-O1 -g -fsanitize=fuzzer-no-link" \
		CXXFLAGS="-O1 -g -fsanitize=fuzzer-no-link" $(BUILD)-fuzz/libraybundle.a
	$(Q)for f in $(FUZZ_SRC); do \
		name=$$(basename $$f .c); corpus=tests/fuzz/corpus/$${name#fuzz_}; \
		clang $(ALL_CPPFLAGS) -std=c11 $(FPFLAGS) -g -O1 -fsanitize=fuzzer,address,undefined -c \
			-o $(BUILD)-fuzz/$$name.o $$f && \
		clang++ -fsanitize=fuzzer,address,undefined -o $(BUILD)-fuzz/$$name \
			$(BUILD)-fuzz/$$name.o $(BUILD)-fuzz/libraybundle.a $(PKG_LIBS) && \
		mkdir -p $(BUILD)-fuzz/corpus-$$name && \
		$(BUILD)-fuzz/$$name -max_total_time=$(FUZZ_SECONDS) $(BUILD)-fuzz/corpus-$$name \
			$$corpus || exit 1; \
	done

test check: $(BUILD)/raybundle $(BUILD)/mkdemo $(BUILD)/ltcfit $(UNIT_BIN) $(TOOL_BIN) $(FUZZ_REPLAY) \
		$(FUZZ_SAN_BIN)
	$(Q)BUILD=$(BUILD) tests/run.sh

# jobs/slurm-array.sh on a one-node Slurm cluster this machine starts (root; installs slurm-wlm
# and munge through scripts/install-deps.sh --farm). Not in `make check`: CI runs it after.
check-farm: $(BUILD)/raybundle $(BUILD)/tests/tools/freeport
	$(Q)BUILD=$(BUILD) tests/run.sh tests/farm/slurm.sh

bench: $(BUILD)/raybundle $(BUILD)/tests/tools/triangles $(BUILD)/tests/tools/freeport
	$(Q)BUILD=$(BUILD) tests/bench.sh

# Golden frames for t0130: only for a change meant to change pixels (see tests/golden/update.sh).
update-golden: $(BUILD)/raybundle $(TOOL_BIN)
	$(Q)BUILD=$(BUILD) tests/golden/update.sh

demo: $(BUILD)/raybundle
	$(Q)$(BUILD)/raybundle render jobs/demo.yaml --preview

# The portable tarball: a build without OpenImageIO in its own directory, its libraries beside
# it (none that a host's Vulkan driver loads too), found through an $$ORIGIN-relative RUNPATH.
# VERSION is git describe's (a v* tag), else the source's version and the commit.
DIST_BUILD ?= $(BUILD)-dist
RB_VERSION_NUM := $(shell sed -n 's/^\#define RB_VERSION "\(.*\)"/\1/p' lib/core/core.h)
DIST_VERSION ?= $(shell v=$$(git describe --tags --match 'v[0-9]*' --dirty 2>/dev/null); \
	if [ -n "$$v" ]; then echo "$${v\#v}"; \
	else echo "$(RB_VERSION_NUM)-g$$(git describe --always --dirty 2>/dev/null || echo unknown)"; fi)
DIST_TARBALL = dist/raybundle-$(DIST_VERSION)-linux-x86_64.tar.xz

dist: $(DEPS_STAMP)
	$(Q)$(MAKE) --no-print-directory BUILD=$(DIST_BUILD) OIIO=0 $(DIST_BUILD)/raybundle
	$(Q)scripts/dist.sh $(DIST_BUILD)/raybundle dist $(DIST_VERSION)

# The tarball on another distribution (a cached Debian 13 chroot) and the GPU check end to end
# on lavapipe. Needs root and Debian's mirrors; .ci/run runs it after make check.
check-dist: dist $(BUILD)/raybundle
	$(Q)tests/dist/check-dist.sh $(DIST_TARBALL) $(BUILD)/raybundle
	$(Q)tests/gpu/selftest.sh --tarball $(DIST_TARBALL)

install: $(BUILD)/raybundle
	install -d "$(DESTDIR)$(BINDIR)" "$(DESTDIR)$(MANDIR)/man1" "$(DESTDIR)$(MANDIR)/man5" \
		"$(DESTDIR)$(DATADIR)/ocio"
	install -m 0755 $(BUILD)/raybundle "$(DESTDIR)$(BINDIR)/"
	install -m 0644 man/*.1 "$(DESTDIR)$(MANDIR)/man1/"
	install -m 0644 man/*.5 "$(DESTDIR)$(MANDIR)/man5/"
	install -m 0644 share/ocio/config.ocio "$(DESTDIR)$(DATADIR)/ocio/"

uninstall:
	rm -f "$(DESTDIR)$(BINDIR)/raybundle" "$(DESTDIR)$(MANDIR)/man1/raybundle.1" \
		"$(DESTDIR)$(MANDIR)/man1/raybundle-bench.1" \
		"$(DESTDIR)$(MANDIR)/man1/raybundle-flicker.1" \
		"$(DESTDIR)$(MANDIR)/man1/raybundle-report.1" \
		"$(DESTDIR)$(MANDIR)/man5/raybundle-job.5" "$(DESTDIR)$(DATADIR)/ocio/config.ocio"

lint:
	$(Q)FORMAT_SRC="$(FORMAT_SRC)" tests/lint.sh

FORMAT_SRC = $(LIB_C) $(LIB_CXX) $(CMD_C) $(wildcard lib/*/*.h cmd/*.h) $(UNIT_SRC) $(TOOL_SRC) \
	$(wildcard tests/fuzz/*.c) tools/mkdemo.c tools/ltcfit.c

format:
	$(Q)clang-format -i $(FORMAT_SRC)

clean:
	rm -rf $(BUILD)

-include $(DEPS) $(FUZZ_SAN_DEPS)
