"""The nonsmooth engine: rigid unilateral contact with Newton impacts and set-valued Coulomb
friction, Moreau–Jean time stepping (:mod:`.moreau_jean`) with the contact impulses of each step
solved as LCPs (:mod:`.impulses`, :mod:`.frictional_contact`); the engine itself is
:mod:`.engine`."""
