# Two commands for a fresh clone:  make lab   (open the course)   make test   (run every test)
# Both create .venv at the repo root when it is missing and install the project into it.

PYTHON ?= python3
VENV   := .venv
BIN    := $(CURDIR)/$(VENV)/bin
STAMP  := $(VENV)/.installed
# nbgrader shells out to `alembic`: the venv's bin/ must be on PATH for anything that runs it.
export PATH := $(BIN):$(PATH)
PORT   ?= 8888
# make lab: the students' own environment (their wheel only, none of this repository's sources)
STUDENT_VENV := .venv-student

.PHONY: setup lab instructor test test-fast bench browser-deps a11y-deps sandbox-deps wheel-deps \
        postgres-deps mathjax-deps hub hub-deps clean

$(STAMP): pyproject.toml
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test,postgres,cluster]'
	@touch $(STAMP)

## setup: create .venv and install everything the instructor's commands need (the course in
## .venv; as root, Debian's bubblewrap, gcc and the Python headers, MathJax), starting no server
setup: $(STAMP) sandbox-deps wheel-deps mathjax-deps
	@echo "setup done: activate with '. .venv/bin/activate' (or run .venv/bin/python -m autograder ...)"

## lab: open the course in JupyterLab as a student: the released notebooks, run in
## $(STUDENT_VENV) with the students' compiled wheel (rebuilt and reinstalled when sources change;
## while it compiles, JupyterLab is already open on an environment without course_lib, and the
## terminal says what it waits for and when the wheel is in)
lab: $(STAMP) wheel-deps
	$(BIN)/python -m autograder lab --role student --student-env $(STUDENT_VENV) --port $(PORT)

## instructor: open JupyterLab on the nbgrader sources, with the formgrader
instructor: $(STAMP) mathjax-deps
	$(BIN)/python -m autograder lab --role instructor --port $(PORT)

## browser-deps: Debian's headless Chromium for the browser tests (never a downloaded browser)
browser-deps:
	@if [ ! -x /usr/bin/chromium ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends chromium >/dev/null 2>&1) \
	      || echo "warning: could not install chromium; browser tests will be skipped"; \
	  else echo "warning: not root, cannot apt-get install chromium; browser tests will be skipped"; fi; \
	fi

## mathjax-deps: Debian's MathJax 2, which the Formgrader serves itself (LaTeX in the marker's
## pages without a CDN); without it the pages ask the CDN, as nbgrader's do
mathjax-deps:
	@if [ ! -f /usr/share/javascript/mathjax/MathJax.js ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends libjs-mathjax >/dev/null 2>&1) \
	      || echo "warning: could not install libjs-mathjax; the Formgrader will load MathJax from its CDN"; \
	  else echo "warning: not root, cannot apt-get install libjs-mathjax; the Formgrader will load MathJax from its CDN"; fi; \
	fi

## a11y-deps: axe-core 4 from the npm registry into .cache/axe/ (git-ignored), injected by the
## browser tests of accessibility (tests/browser/test_accessibility.py); Debian's nodejs and npm
## first when missing
AXE_DIR := .cache/axe
AXE_JS  := $(AXE_DIR)/node_modules/axe-core/axe.min.js
a11y-deps:
	@if ! command -v npm >/dev/null 2>&1; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null 2>&1) \
	      || echo "warning: could not install nodejs/npm; the accessibility tests will be skipped"; \
	  else echo "warning: not root, cannot apt-get install npm; the accessibility tests will be skipped"; fi; \
	fi
	@if [ ! -f $(AXE_JS) ] && command -v npm >/dev/null 2>&1; then \
	  mkdir -p $(AXE_DIR) && npm install --silent --no-audit --no-fund --prefix $(AXE_DIR) axe-core@4 \
	    || echo "warning: npm could not install axe-core; the accessibility tests will be skipped"; \
	fi

## sandbox-deps: Debian's bubblewrap, the grading sandbox, and libseccomp2, its seccomp filter
## (autograder/isolation)
sandbox-deps:
	@if [ ! -x /usr/bin/bwrap ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends bubblewrap >/dev/null 2>&1) \
	      || echo "warning: could not install bubblewrap; the grader cannot isolate students' code"; \
	  else echo "warning: not root, cannot apt-get install bubblewrap; the grader cannot isolate students' code"; fi; \
	fi
	@if ! /sbin/ldconfig -p 2>/dev/null | grep -q 'libseccomp\.so\.2'; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends libseccomp2 >/dev/null 2>&1) \
	      || echo "warning: could not install libseccomp2; the grader cannot filter students' system calls"; \
	  else echo "warning: not root, cannot apt-get install libseccomp2; the grader cannot filter students' system calls"; fi; \
	fi

## postgres-deps: Debian's PostgreSQL server binaries, for the tests of the gradebook on PostgreSQL
## (the tests start a throw-away server of their own; the packaged cluster is not used)
postgres-deps:
	@if ! ls /usr/lib/postgresql/*/bin/initdb >/dev/null 2>&1; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends postgresql >/dev/null 2>&1) \
	      || echo "warning: could not install postgresql; the PostgreSQL gradebook tests will be skipped"; \
	  else echo "warning: not root, cannot apt-get install postgresql; the PostgreSQL gradebook tests will be skipped"; fi; \
	fi

## wheel-deps: a C compiler and the Python headers, to compile the students' wheel (Cython)
wheel-deps:
	@if ! command -v gcc >/dev/null 2>&1 || [ ! -f "$$($(BIN)/python -c 'import sysconfig; print(sysconfig.get_paths()["include"])')/Python.h" ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends gcc python3-dev >/dev/null 2>&1) \
	      || echo "warning: could not install gcc/python3-dev; the student wheel cannot be built"; \
	  else echo "warning: no gcc or Python headers (apt-get install gcc python3-dev); the student wheel cannot be built"; fi; \
	fi

## hub-deps: Debian's configurable-http-proxy (JupyterHub's proxy), python3-venv (the
## students' and instructors' environments on the hub are venvs of Debian's /usr/bin/python3)
## and acl (setfacl: the graders read the exchange's inbound through a default ACL)
hub-deps:
	@if [ ! -x /usr/bin/configurable-http-proxy ] || [ ! -x /usr/bin/setfacl ] || ! /usr/bin/python3 -c 'import ensurepip, venv' >/dev/null 2>&1; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends node-configurable-http-proxy python3-venv acl >/dev/null 2>&1) \
	      || echo "warning: could not install node-configurable-http-proxy/python3-venv; the hub test will be skipped"; \
	  else echo "warning: not root, cannot apt-get install node-configurable-http-proxy; the hub test will be skipped"; fi; \
	fi

## hub: the course on a JupyterHub on this machine (as root; see deploy/README.md).
## HUB_STATE=/srv/4f9-hub HUB_PORT=8000 HUB_IP=127.0.0.1 by default
HUB_STATE ?= /srv/4f9-hub
HUB_PORT  ?= 8000
HUB_IP    ?= 127.0.0.1
hub: $(STAMP) hub-deps wheel-deps sandbox-deps
	@test "$$(id -u)" = 0 || { echo "make hub runs as root (it creates Unix users and runs a setuid spawner): sudo make hub, or make hub in a root shell"; exit 2; }
	$(BIN)/python deploy/hub.py --state $(HUB_STATE) up --port $(HUB_PORT) --ip $(HUB_IP)

# nbmake (a test dependency no test uses) would import nbformat, and with it a parser that
# costs 2 s of CPU, in every pytest process before tests/conftest.py can put it off
PYTEST := $(BIN)/python -m pytest -p no:nbmake

## test: the whole suite (library, notebooks, grading bank, browser): 15 minutes measured on 2 quiet cores
test: $(STAMP) browser-deps a11y-deps sandbox-deps wheel-deps postgres-deps hub-deps mathjax-deps
	@echo "make test: the whole suite, about 30 minutes on a fresh clone on 2 cores, the real hub's term and 30-user burst and the students' wheel probe included (one dot per test; make test-fast: about 1 minute)"
	$(PYTEST) -n 2 --dist loadgroup -q

## test-fast: what a change to an exercise can break, in about a minute of wall time on 2 quiet
## cores: the library against its oracles, the judging and every registry rule, the notebooks'
## contract, marks and counts (test_facts), their visible and hidden tests run in each source
## notebook, the honest bank judged in process, new-exercise on a scratch copy, the students'
## wheel's name rules, the docs' links, ruff
FAST_TESTS := tests/course_lib tests/grading/test_judging.py tests/grading/test_handback_page.py \
              tests/grading/test_cell_verdict.py tests/grading/test_honest_in_process.py \
              tests/notebooks/test_contract.py tests/notebooks/test_facts.py \
              tests/notebooks/test_new_exercise.py tests/notebooks/test_items_ask_first.py \
              tests/notebooks/test_student_wheel_guard.py tests/notebooks/test_q1_q2_facts.py \
              tests/notebooks/test_q4_items.py tests/notebooks/test_q5_q6_items.py \
              tests/notebooks/test_execute_sources.py tests/test_docs_links.py tests/test_lint.py
# no xdist group among them: worksteal hands a long test's neighbours to the idle worker
test-fast: $(STAMP)
	@echo "make test-fast: library, judging, notebooks, marks and counts, honest bank, docs' links (about a minute on 2 quiet cores; make test runs everything)"
	$(PYTEST) -n 2 --dist worksteal -q $(FAST_TESTS)

## bench: benchmarks against peers measured in the same run (writes benchmarks/results.md)
bench: $(STAMP)
	$(BIN)/python -m benchmarks

clean:
	rm -rf $(VENV) $(STUDENT_VENV) .pytest_cache test-artifacts
