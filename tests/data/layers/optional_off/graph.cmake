# A build with the optional area 'opt' switched off (as TRIPODAL_DDS=OFF leaves out dds): its
# folders exist but belong to no target, and the checker skips them; 'stray' is still reported.
set(TRIPODAL_AREAS "low")
set(TRIPODAL_DISABLED_AREAS "opt")
set(TRIPODAL_AREA_low_PUBLIC "")
set(TRIPODAL_AREA_low_PRIVATE "")
