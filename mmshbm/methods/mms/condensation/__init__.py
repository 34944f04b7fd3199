"""What only MMS-HBM condenses: the complex condensation of a damped structure onto its
massless DOFs with the forced/EPMC right-hand sides (:mod:`.damped_condense`, compiled
modal kernel in :mod:`._damped_modal_kernels`) and the pole unknowns of the conservative
condensation (:mod:`.poles`). The conservative condensation itself is shared with the
reduced penalty method (:mod:`mmshbm.harmonic.condense`)."""
