# The study as make targets: each stage's file depends on the files of the stages before it and on
# the config, so `make -f pipelines/paper.mk` reruns only what is stale. Every stage also checks
# its own fingerprint, and does nothing when its inputs are unchanged; the `touch` then tells
# make so.
#
#   make -f pipelines/paper.mk                      # configs/paper.yaml → out/paper/report
#   make -f pipelines/paper.mk CONFIG=configs/quick.yaml OUT=out/quick
#   make -f pipelines/paper.mk -j1 sweep            # one stage
CONFIG ?= configs/paper.yaml
OUT ?= out/paper
SLIDESTACK ?= target/release/slidestack

all: $(OUT)/report/index.html
motions: $(OUT)/motions.h5
sweep: $(OUT)/sweep.h5
tnew: $(OUT)/tnew.h5
fit: $(OUT)/fit.h5
report: $(OUT)/report/index.html
.PHONY: all motions sweep tnew fit report

$(SLIDESTACK):
	cargo build --release

$(OUT)/motions.h5: $(CONFIG) | $(SLIDESTACK)
	$(SLIDESTACK) motions $(CONFIG) --out $(OUT)
	@touch $@

$(OUT)/sweep.h5: $(OUT)/motions.h5 $(CONFIG)
	$(SLIDESTACK) sweep $(CONFIG) --out $(OUT)
	@touch $@

$(OUT)/tnew.h5: $(OUT)/sweep.h5
	$(SLIDESTACK) tnew $(CONFIG) --out $(OUT)
	@touch $@

$(OUT)/fit.h5: $(OUT)/tnew.h5
	$(SLIDESTACK) fit $(CONFIG) --out $(OUT)
	@touch $@

$(OUT)/report/index.html: $(OUT)/fit.h5 $(OUT)/motions.h5
	$(SLIDESTACK) report $(CONFIG) --out $(OUT)
