"""MMS-HBM: the massless mixed shooting-harmonic balance method.

One module per problem: the conservative backbone (:mod:`.conservative`, its family events
in :mod:`.family`, its time signals in :mod:`.signals`), the damped rows shared by the
forced response, EPMC and phase resonance (:mod:`.damped`, :mod:`.forced`, :mod:`.epmc`,
:mod:`.phase_resonance`), Floquet stability (:mod:`.stability`), the filtered passage of an
internal resonance (:mod:`.filtered`) and the friction problems (:mod:`.friction_forced`,
:mod:`.friction_epmc`, :mod:`.friction_stability`).
"""
