//! The examples that end each command's `--help` (clap's `after_help`),
//! one constant per command. Each line after `Examples:` that starts with
//! `irtp ` is a command the tests run as printed, at reduced size
//! (crates/irtp-cli/tests/it/help.rs): an example that stops running fails
//! the tests.

/// `irtp analytic`.
pub const ANALYTIC: &str = "\
Examples:
  irtp analytic                                    # P_s(v) of the paper's tan medium, Sigma = 3
  irtp analytic --drag tanh --sigma 0.6 --out runs/r0
  irtp analytic --drag linear --noise rpt:sigma=1,alpha=1,beta=2 --rate 1";

/// `irtp simulate`.
pub const SIMULATE: &str = "\
Examples:
  irtp simulate --particles 20000 --t-max 50 --out runs/sim    # <v²>(t), P_s(v), D_eff
  irtp simulate --method euler --drag tanh --sigma 0.6 --t-max 20
  irtp simulate --reset-period 1 --t-max 50        # sharp (periodic) resetting";

/// `irtp mfpt`.
pub const MFPT: &str = "\
Examples:
  irtp mfpt --v0 0 --vt 1                          # tau from the backward equations
  irtp mfpt --v0 0 --vt 1 --method exact --particles 20000
  irtp mfpt --v0 0 --xt 1 --reset-position 0 --rate 1   # a search: first passage of x to 1";

/// `irtp mfpt scan`.
pub const MFPT_SCAN: &str = "\
Examples:
  irtp mfpt scan --v0 0 --over vt --from 0.2 --to 1.2 --points 11
  irtp mfpt scan --v0 0 --vt 1 --over rate --from 0.1 --to 10 --log --out runs/scan";

/// `irtp mfpt optimize`.
pub const MFPT_OPTIMIZE: &str = "\
Examples:
  irtp mfpt optimize --v0 0 --vt 1                 # r* and tau(r*), or r* = 0
  irtp mfpt optimize --v0 0 --vt 0.5 --drag tanh --sigma 0.6";

/// `irtp mfpt distribution`.
pub const MFPT_DISTRIBUTION: &str = "\
Examples:
  irtp mfpt distribution --v0 0 --vt 1 --out runs/fpt      # S(t), f(t), variance
  irtp mfpt distribution --v0 0 --vt 1 --method exact --particles 20000";

/// `irtp fp`.
pub const FP: &str = "\
Examples:
  irtp fp stationary --rate 2                      # P_s(v), <v²>, D_eff
  irtp fp transient --t-max 5                      # <v²>(t) from v = 0
  irtp fp msd --t-max 100                          # <x²>(t) and its local exponent";

/// `irtp fp stationary`.
pub const FP_STATIONARY: &str = "\
Examples:
  irtp fp stationary                               # the paper's tan medium at r = 2
  irtp fp stationary --drag tanh --sigma 0.6 --rate 0.5 --out runs/fp";

/// `irtp fp transient`.
pub const FP_TRANSIENT: &str = "\
Examples:
  irtp fp transient --t-max 5 --out runs/transient
  irtp fp transient --t-max 5 --scheme paper       # the paper's explicit scheme";

/// `irtp fp msd`.
pub const FP_MSD: &str = "\
Examples:
  irtp fp msd --t-max 100
  irtp fp msd --drag tanh --sigma 0.6 --rate 0.5 --out runs/msd";
