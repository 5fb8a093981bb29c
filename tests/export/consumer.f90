! The exported model called from Fortran through bind(C), the way an MFiX usr_drag (drag_usr) would: the module
! model.f90 written by cgd-export, the functions compiled once from impl.c. Reads "phi delta_m alpha" lines on
! stdin, prints "h a H beta_bar/beta_micro" (tests/export/export_test.sh).
program consumer
  use, intrinsic :: iso_c_binding, only: c_double
  use cgd_model
  implicit none
  real(c_double) :: phi, delta_m, alpha
  integer :: ios
  do
    read (*, *, iostat=ios) phi, delta_m, alpha
    if (ios /= 0) exit
    ! a usr_drag would do: lDgA = beta_micro(EPg, ...) * cgd_model_correction(1 - EPg, cbrt(cell volume), alpha)
    write (*, '(4(ES26.17E3,1X))') cgd_model_master_h(phi), cgd_model_master_a(phi), cgd_model_H(phi, delta_m), &
      cgd_model_correction(phi, delta_m, alpha)
  end do
end program consumer
