# The study as make targets, on one machine (pipelines/slurm-submit.sh for a cluster):
#
#   make -f pipelines/paper.mk                          # configs/paper.yaml -> out/paper/report
#   make -f pipelines/paper.mk CONFIG=configs/quick.yaml OUT=out/quick
#   make -f pipelines/paper.mk CONFIG=configs/ida-quick.yaml OUT=out/ida-quick   # motions, ida, report
#   make -f pipelines/paper.mk CONFIG=configs/mdof-floors-quick.yaml OUT=out/floors  # … floors, report
#   make -f pipelines/paper.mk sweep                    # up to one stage
#   make -f pipelines/paper.mk -B FORCE=1               # recompute every stage
#
# make runs exactly the stages the config configures, as `slidestack run` does: motions and the
# report always, sweep and tnew with a `grid` section, fit when that grid has enough cases to fit
# a design equation, ida with an `ida:` section, floors with a `floor_spectra:` section. It asks the binary which
# (`slidestack status --format make` into OUT/make/stages.mk, remade when the config or the
# binary changes) before it decides anything else.
#
# Works from any directory (CONFIG and OUT are taken from the current one, as slidestack does).
#
# Each stage file depends on the files of the stages before it, the config and the binary, so a
# new config or binary makes make ask every stage after it; a stage asked does nothing when the
# fingerprint of its inputs is unchanged, and `touch` then tells make it is current. The motions
# stage is asked on every make: it hashes every record file the config names (SHA-256) and
# rewrites motions.h5 only when a record, the config's sections or the tool version changed, and
# only then do the later stages run again. (make cannot list the record files itself: the config
# names them, relative to its own folder.) The report is one of these stages: it keeps the
# fingerprint of its inputs in OUT/report/FINGERPRINT and is rebuilt only when they change.
#
# make -j is safe: the stages form one chain, and every stage holds the output directory's lock
# (OUT/.slidestack.lock) while it runs, so two makes into the same OUT wait for each other (the
# stage that waits prints "waiting for PID ..."), and the second finds the files up to date.
#
# The binary is built (cargo build --release) only when it is missing; after changing the
# sources, run cargo build --release yourself, or give SLIDESTACK=/path/to/slidestack.

ROOT := $(patsubst %/pipelines/,%,$(dir $(abspath $(lastword $(MAKEFILE_LIST)))))
CONFIG ?= $(ROOT)/configs/paper.yaml
OUT ?= out/paper
SLIDESTACK ?= $(ROOT)/target/release/slidestack
# FORCE=1 passes --force to every stage that runs (with -B: recompute everything).
FORCE ?=
STAGE_FLAGS := $(if $(filter 1 yes true,$(FORCE)),--force)

all: $(OUT)/report/index.html
motions: $(OUT)/motions.h5
sweep: $(OUT)/sweep.h5
tnew: $(OUT)/tnew.h5
fit: $(OUT)/fit.h5
ida: $(OUT)/ida.h5
floors: $(OUT)/floors.h5
report: $(OUT)/report/index.html
.PHONY: all motions sweep tnew fit ida floors report always

# STAGES: the stages the config configures, in order (written by the binary; under a name of
# its own per make, then renamed, so two makes into one OUT at once both read a whole file).
STAGES_MK := $(OUT)/make/stages.mk
$(STAGES_MK): $(CONFIG) $(SLIDESTACK)
	@mkdir -p '$(@D)'
	@tmp='$@.'$$$$.tmp; '$(SLIDESTACK)' status '$(CONFIG)' --out '$(OUT)' --format make >"$$tmp" && \
	  mv -f "$$tmp" '$@'
include $(STAGES_MK)
# Each stage's file; the report depends on every other configured stage's.
file_motions := $(OUT)/motions.h5
file_sweep := $(OUT)/sweep.h5
file_tnew := $(OUT)/tnew.h5
file_fit := $(OUT)/fit.h5
file_ida := $(OUT)/ida.h5
file_floors := $(OUT)/floors.h5
REPORT_INPUTS := $(foreach s,$(filter-out report,$(STAGES)),$(file_$(s)))

# Built only when missing, also under make -B (which remakes every target, this one included).
$(SLIDESTACK):
	@if [ ! -x '$@' ]; then \
	  echo "paper.mk: no binary at $@: building it (cargo build --release in $(ROOT))"; \
	  cd '$(ROOT)' && cargo build --release; \
	fi

# Asked every time (prerequisite `always`); rewrites motions.h5 only when its inputs changed,
# and no touch here, so the later stages see a newer motions.h5 only then.
$(OUT)/motions.h5: $(CONFIG) $(SLIDESTACK) always
	'$(SLIDESTACK)' motions '$(CONFIG)' --out '$(OUT)' $(STAGE_FLAGS)

$(OUT)/sweep.h5: $(OUT)/motions.h5 $(CONFIG) $(SLIDESTACK)
	'$(SLIDESTACK)' sweep '$(CONFIG)' --out '$(OUT)' $(STAGE_FLAGS)
	@touch -c '$@'

$(OUT)/tnew.h5: $(OUT)/sweep.h5 $(OUT)/motions.h5 $(CONFIG) $(SLIDESTACK)
	'$(SLIDESTACK)' tnew '$(CONFIG)' --out '$(OUT)' $(STAGE_FLAGS)
	@touch -c '$@'

$(OUT)/fit.h5: $(OUT)/tnew.h5 $(CONFIG) $(SLIDESTACK)
	'$(SLIDESTACK)' fit '$(CONFIG)' --out '$(OUT)' $(STAGE_FLAGS)
	@touch -c '$@'

$(OUT)/ida.h5: $(OUT)/motions.h5 $(CONFIG) $(SLIDESTACK)
	'$(SLIDESTACK)' ida '$(CONFIG)' --out '$(OUT)' $(STAGE_FLAGS)
	@touch -c '$@'

$(OUT)/floors.h5: $(OUT)/motions.h5 $(CONFIG) $(SLIDESTACK)
	'$(SLIDESTACK)' floors '$(CONFIG)' --out '$(OUT)' $(STAGE_FLAGS)
	@touch -c '$@'

$(OUT)/report/index.html: $(REPORT_INPUTS) $(CONFIG) $(SLIDESTACK)
	'$(SLIDESTACK)' report '$(CONFIG)' --out '$(OUT)' $(STAGE_FLAGS)
	@touch -c '$@'
