"""A cut's geometry, from the job's rulings to the wire's pose along every pass.

* :mod:`.passes` — refined rulings, kerf offset, lead-in/out, the passes of a cut;
* :mod:`.entry` — straight entry and exit moves of a profile;
* :mod:`.closed` — loops entered through a slit, in one pass or two;
* :mod:`.kerf`, :mod:`.order` — kerf compensation, the orders of cuts a wire can make;
* :mod:`.wire_pose` — the wire's roll, slide and IK branch along a pass (``SearchOptions``);
* :mod:`.clearance` — arm, bow and wire against the stock and the table (``Cell``, once a plan);
* :mod:`.wire_geometry` — chords, slides, tool poses, the speed factor;
* :mod:`.cutpath` — the value types (refined cut, pass).
"""
