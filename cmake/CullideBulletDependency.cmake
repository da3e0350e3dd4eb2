# cullide_add_bullet_target(<double> [GLOBAL]): the imported target CullideBullet::Bullet, the Bullet the adapter
# links, made from what the caller found: CMake's FindBullet (BULLET_INCLUDE_DIRS, BULLET_LIBRARIES) or, with
# <double> true, pkg-config's bullet-float64 (CULLIDE_BULLET64_*; BT_USE_DOUBLE_PRECISION). The build tree and the
# installed CullideBulletConfig.cmake both call it, so the exported adapter target names CullideBullet::Bullet and no
# path of the machine it was built on: a consumer's own find of Bullet decides where Bullet is.
function(cullide_add_bullet_target double)
  if(TARGET CullideBullet::Bullet)
    return()
  endif()
  add_library(CullideBullet::Bullet INTERFACE IMPORTED ${ARGN})
  if(double)
    target_include_directories(CullideBullet::Bullet INTERFACE ${CULLIDE_BULLET64_INCLUDE_DIRS})
    target_link_libraries(CullideBullet::Bullet INTERFACE ${CULLIDE_BULLET64_LINK_LIBRARIES})
    target_compile_definitions(CullideBullet::Bullet INTERFACE BT_USE_DOUBLE_PRECISION)
  else()
    target_include_directories(CullideBullet::Bullet INTERFACE ${BULLET_INCLUDE_DIRS})
    target_link_libraries(CullideBullet::Bullet INTERFACE ${BULLET_LIBRARIES})
  endif()
endfunction()
