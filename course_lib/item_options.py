"""The options of every multiple-choice item, in the canonical order (the registry's key
letters refer to this order; each student sees them shuffled:
:func:`course_lib.variants.option_order`).

Kept here rather than in the notebooks so that an item's options cell shows only the call
``mine.options("q5_item1")`` and the student reads the options once, lettered in their own order.
Only the texts: which options are right is known to the grader alone.
"""

OPTIONS = {
    'q1_item1': (
        'the attenuation coefficient of the one small piece of tissue lying directly '
        'above that detector point',
        'the X-rays that tissue at the depth in focus scatters back towards the tube, as '
        'in a reflection image',
        'the attenuation coefficient summed along the straight ray from the source to '
        'that detector point',
        'the density of the tissue in the one plane of the body on which the X-ray tube '
        'is focused',
    ),
    'q1_item2': (
        'the attenuation summed along one ray through the patient, like one point of a '
        'radiograph',
        'the mass density of the tissue in that voxel, measured in grams per cubic '
        'centimetre',
        'the X-ray dose the tissue in that voxel absorbed while the scanner rotated '
        'around it',
        'the attenuation coefficient of one small voxel, as a number relative to water '
        '(HU)',
    ),
    'q1_item3': (
        'how strongly 511 keV photons are attenuated at that point, like a CT at higher '
        'energy',
        "how many tracer decays happen near that point: the tracer's local concentration",
        'how many annihilation photons are scattered at that point on their way out of '
        'the body',
        "the density of the tissue at that point, measured with the tracer's own gamma "
        'rays',
    ),
    'q1_item4': (
        'the echo scattered back by impedance changes near that point, weakened by the '
        'tissue above',
        'the acoustic impedance Z = ρc of the tissue at that point, measured by the '
        'returning echo',
        'the total attenuation the pulse has suffered along the beam from the probe down '
        'to that point',
        "the speed of sound at that point, worked out by the scanner from the echo's time"
        ' of arrival',
    ),
    'q1_item5': (
        'the CT measures the attenuation along every line through the body, so the PET '
        'counts can be corrected for it',
        "the CT's X-rays excite the tracer so that it decays faster, which raises the PET"
        ' count rate and shortens the scan',
        'the CT shows the anatomy sharply; registered with the blurrier PET image it '
        'shows where the tracer is taken up',
        'PET and CT use the same detectors, so one combined acquisition gives the patient'
        ' half the dose of two scans',
    ),
    'q1_item6': (
        'deeper: the liver attenuates the pulse, so its echo takes longer to return and '
        'is drawn further down',
        'closer to the probe: sound crosses the liver faster than the water it replaces, '
        'so its echo is early',
        'at the same depth: the speed error distorts the block itself, but the floor is a'
        ' separate object',
        'at the same depth, only fainter: the liver changes how bright the echo is, not '
        'when it arrives',
    ),
    'q2_item1': (
        "so that each dynode glows when it is struck, and the next dynode's coating "
        'detects that light',
        'so that electrons missing a dynode are pushed back to the photocathode for a '
        'second pass',
        'so that electrons are pulled onto the next dynode fast enough for each to free '
        'several more',
        'so that the field across the tube stops gamma photons from reaching the anode '
        'directly',
    ),
    'q2_item2': (
        'the height of each output pulse is proportional to the energy the gamma photon '
        'deposited',
        'the flash fades in about 0.25 microseconds and the tube responds in nanoseconds:'
        ' it is fast',
        'NaI(Tl) is dense, so a crystal about 1 cm thick stops most 140 keV photons: '
        'high efficiency',
        'the tubes are small, so many more of them fit behind one crystal than '
        'solid-state photodiodes',
        'the tubes need no high-voltage supply, because the light itself frees all of the'
        ' electrons',
    ),
    'q2_item3': (
        'the energy a photon has lost tells the camera how deep in the patient it was '
        'emitted',
        'an energy window on the pulse height rejects photons that were Compton-scattered',
        'photons from the wrong direction have the wrong energy, so no collimator is '
        'needed',
        'pulses of high-energy photons are shorter, so the detector can count them faster',
    ),
    'q2_item4': (
        'the resolution and the number of photons detected both improve: the holes guide '
        'the photons better',
        'the resolution at the face stays d and gets worse everywhere else, because the '
        'path is longer',
        'the resolution gets worse, because photons travel further through the lead and '
        'scatter more',
        'the resolution improves at every depth z > 0, but fewer photons get through each'
        ' hole',
    ),
    'q2_item5': (
        'overstates it: an open hole passes only photons that cross both its mouth and '
        'its exit',
        'is exact: every hole inside the cut-off passes all of the photons that fall on '
        'its mouth',
        'understates the fraction: holes just outside the cut-off still pass most of '
        'their photons',
        'is exact for every ring, because the holes are parallel to the axis and so to '
        'the photons',
    ),
    'q3_item1': (
        'At the mid-point of the edge: the table names only the edge, so each vertex goes'
        ' to its centre.',
        'Where the data, varying linearly along the edge between its two end values, '
        'equal the iso-level.',
        'At the end whose value is nearer to the iso-level, so that every vertex lies on '
        'a measured sample.',
        'At a fraction of the edge stored in the table for the case, the same in every '
        'cell of that case.',
    ),
    'q3_item2': (
        '23 classes, of which 22 need triangles',
        '15 classes, and every one of the 15 needs triangles',
        '15 classes, of which 14 need triangles',
        '16 classes, of which 14 need triangles',
    ),
    'q3_item3': (
        '4, 6, 7, 10, 12, 13',
        '8, 9, 10, 11, 12, 13, 14',
        '7, 10 and 13 only',
        '3, 6, 7, 10, 12, 13',
    ),
    'q3_item4': (
        'On one face the inside corners sit on a diagonal; its four crossings pair up in '
        'two ways, and two cells pairing them differently leave a gap.',
        'The case has so many triangles that some must cross inside the cell, so the '
        'surface meets itself there and its volume comes out wrong.',
        'A sample equals the iso-level, so a vertex lands on a corner; its triangles have'
        ' zero area and show up as small holes in the shaded surface.',
        'A case and its complement share their triangles, so one of the two has normals '
        'pointing inwards, and the back-facing patch looks like a hole.',
    ),
    'q3_item5': (
        'closed, free of self-intersections, manifold, and convex',
        "closed, manifold, consistently ordered, with $\\hat{\\mathbf n}$ each triangle's "
        'own unit normal',
        'closed, free of self-intersections, manifold, and consistently ordered',
        'free of self-intersections, manifold and consistently ordered, with gaps allowed'
        ' (their prisms cancel)',
    ),
    'q4_item1': (
        '$3N + 1$, as for a chain of Bézier pieces that share only their end points.',
        '$N + 3$, because consecutive segments overlap in three points.',
        '$4N$, because every segment needs a geometry matrix of four points of its own.',
        '$N + 1$, because each segment runs from one control point to the next one.',
    ),
    'q4_item2': (
        'Like a Bézier curve, a B-spline curve starts on its first control point and ends'
        ' on its last.',
        'A Catmull-Rom segment passes through the second and third points of its geometry'
        ' matrix.',
        'The Catmull-Rom weights are never negative, so the curve stays in the convex '
        'hull of its points.',
        'Where segments join, the uniform cubic B-spline is C² but the Catmull-Rom spline'
        ' only C¹.',
        'Both splines take the same four-point geometry matrix; only the basis matrix '
        'differs.',
    ),
    'q4_item4': (
        'At $\\mathbf c$, moving with velocity $\\mathbf c - \\mathbf b$ and with zero '
        'acceleration.',
        'At $\\tfrac13(\\mathbf b + 2\\mathbf c)$, at rest, accelerating from $\\mathbf c$ '
        'back towards $\\mathbf b$.',
        'At $\\mathbf c$, at rest, with its acceleration pointing from $\\mathbf c$ back '
        'towards $\\mathbf b$.',
        'At $\\tfrac13(2\\mathbf b + \\mathbf c)$, at rest, accelerating from $\\mathbf b$ on'
        ' towards $\\mathbf c$.',
    ),
    'q4_item5': (
        'Catmull-Rom with $\\mathbf d = \\mathbf b$',
        'Catmull-Rom with $\\mathbf d = 2\\mathbf c - \\mathbf b$',
        'B-spline with $\\mathbf d = \\mathbf b$',
        'B-spline with $\\mathbf d = 2\\mathbf c - \\mathbf b$',
        'B-spline with $\\mathbf d = \\mathbf c$',
    ),
    'q4_item7': (
        '$\\mathbf d = 2\\mathbf c - \\mathbf b$: of the two rules, only this one makes the '
        'Catmull-Rom curve reach $\\mathbf c$.',
        "$\\mathbf d = 2\\mathbf c - \\mathbf b$: it makes $\\mathbf p''(1)$ vanish, so the "
        'curve meets $\\mathbf c$ without bending.',
        "$\\mathbf d = \\mathbf b$: the curve still ends on $\\mathbf c$, and $\\mathbf p'(1)"
        ' = \\mathbf 0$ imposes no end direction.',
        '$\\mathbf d = \\mathbf b$: it halts the curve two thirds of the way to $\\mathbf '
        'c$, before the unknown region.',
    ),
    'q4_item8': (
        '$\\mathbf d = \\mathbf b$ ends the path exactly on $\\mathbf c$, at rest; $\\mathbf '
        'd = 2\\mathbf c - \\mathbf b$ carries it on beyond $\\mathbf c$.',
        '$\\mathbf d = \\mathbf b$ stops the camera at rest short of $\\mathbf c$; $\\mathbf '
        'd = 2\\mathbf c - \\mathbf b$ ends on $\\mathbf c$, still moving.',
        'Both rules end the path exactly on $\\mathbf c$; they differ only in how fast the'
        ' camera is moving when it gets there.',
        'Neither rule reaches $\\mathbf c$: a uniform cubic B-spline never passes through '
        'any of the points it is given.',
    ),
    'q5_item1': (
        "It gives the highlight more of the surface's own colour $c_\\lambda$, as in the "
        'diffuse term.',
        'It shrinks the highlight and sharpens it, while the peak value $I_p k_s$ stays '
        'the same.',
        'It moves the highlight towards the point where the surface faces the light '
        '($\\mathbf L\\cdot\\mathbf N = 1$).',
        'It brightens the whole highlight, since raising the cosine to a higher power '
        'makes it grow.',
    ),
    'q5_item2': (
        'always, because $\\mathbf H$ never needs normalising, wherever the light and the '
        'viewer are',
        'always, because $\\mathbf N\\cdot\\mathbf H$ is never negative, so the clamp at '
        'zero can be left out entirely',
        'when light and viewer are both very far away, so that $\\mathbf H$ is one vector '
        'for the whole scene',
        'when the light is close to the surface, because $\\mathbf H$ then varies slowly '
        'across it',
    ),
    'q5_item3': (
        'Monitors have only three primaries, so no renderer could ever compute a correct '
        'colour.',
        'The specular term carries no $c_\\lambda$, so every highlight comes out in the '
        'wrong colour.',
        'Light and surface spectra are cut to three samples before they are multiplied '
        'together.',
        'Eight bits per channel are too few, so nearby colours are rounded to the same '
        'value.',
    ),
    'q5_item4': (
        'sample both spectra at $n$ wavelengths, apply the model at each, and convert to '
        'RGB last',
        "raise the specular exponent $n$, so that the highlight samples the light's "
        'spectrum more finely',
        'for lamps with narrow lines, average each spectrum over the band of each sample '
        'first',
        'store each RGB channel with 16 bits instead of 8, so that fine colour steps '
        'survive',
    ),
    'q6_item1': (
        'Its only job is to stop the rasteriser writing outside the frame buffer, so the '
        'near and far planes are optional extras.',
        'The far plane removes distant objects that would only alias, and moving the near'
        ' plane back gives a cut-away view.',
        'Polygons behind the viewer are harmless, since the divide by a negative $w$ '
        'pushes them off the screen anyway.',
        'Once a polygon is clipped, every one of its vertices has $w = 1$, so no divide '
        'by $w$ is needed any more.',
    ),
    'q6_item2': (
        'Screen coordinates do not exist until the whole polygon has been clipped, so '
        'there is nothing else to test.',
        'Division by $w$ loses precision near the far plane, so tests after the divide '
        'misclassify vertices there.',
        'The six inequalities are the same for every camera, and a rejected polygon never'
        ' pays for the divide.',
        'The near and far planes can only be written as inequalities in $Z$ and $w$, '
        'never in $z_s$.',
    ),
    'q6_item3': (
        'B is the larger triangle: it is nearer the viewer, and nearer things are drawn '
        'bigger.',
        'A is larger in the world and further away, yet neither covers any area on the '
        'screen.',
        'They are the same size in the world, because their $(x_s, y_s)$ coordinates '
        'agree.',
        'A is larger in the world, so it also covers more of the screen than B does.',
    ),
    'q6_item4': (
        'Once per object, before the viewing transformation, since transformations keep '
        'triangles as triangles.',
        'Just before clipping, since clipping a triangle against a plane always leaves a '
        'triangle.',
        'During rasterisation, one scanline at a time, wherever a polygon has more than '
        'one span.',
        'Just after clipping, since a clipped triangle may have more than three vertices '
        'again.',
    ),
}
